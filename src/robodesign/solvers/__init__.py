"""Inner solvers: inverse kinematics onto tolerated poses and collision-free joint-space planning."""
from robodesign.solvers.ik import IKResult, solve_ik
from robodesign.solvers.planning import PlanResult, available_planners, check_path, plan_path

__all__ = ["IKResult", "solve_ik", "PlanResult", "plan_path", "check_path", "available_planners"]
