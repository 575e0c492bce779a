import sys, time, collections
src = sys.argv[1]
sys.path.insert(0, src + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.design.goal_planner as gp
from robodesign.solvers import planning, timing, sequencing, static_validity, pair_certificates, toppra_loop, blended_path
from robodesign.model import collision_cull
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
T = collections.defaultdict(float); C = collections.Counter()
pc = time.process_time
def wrap(obj, name, label):
    f = getattr(obj, name)
    def g(*a, **k):
        t0 = pc()
        try: return f(*a, **k)
        finally: T[label] += pc() - t0; C[label] += 1
    setattr(obj, name, g)
wrap(gp.GoalPlanner, "choose_and_plan", "PLAN")
wrap(gp.GoalPlanner, "time_parameterize", "TIMING")
wrap(sequencing, "choose", "p.choose")
wrap(planning, "plan_path", "p.plan_path")
wrap(planning._Memoized, "_chunk_first_invalid", "p.chunk")
wrap(collision_cull.CollisionCuller, "survivors", "p.survivors")
wrap(pair_certificates.PairCertificates, "pending", "p.pending")
wrap(pair_certificates.PairCertificates, "ask", "p.ask")
wrap(collision_cull.CollisionCuller, "collides", "p.collides")
wrap(timing, "_toppra_profile", "t.toppra_profile")
wrap(timing, "_fit_limits", "t.fit_limits")
wrap(timing, "sample_torques", "t.sample_torques")
wrap(timing, "_sample", "t.sample")
wrap(timing._PathTerms, "__init__", "t.PathTerms")
wrap(timing, "pass_velocities", "t.pass")
wrap(timing, "velocity_xbound", "t.xbound")
import robodesign.model.rnea_batch as rb
for mod in (timing, static_validity):
    wrap(mod, "rnea_rows", f"rnea[{mod.__name__.split('.')[-1]}]")
wrap(timing._ToppraMotion, "_at", "t.motion_at")
R = int(sys.argv[2]) if len(sys.argv) > 2 else 3
for r in range(R):
    for s in range(20):
        Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
n = 20 * R
for k in sorted(T, key=lambda k: -T[k]):
    print(f"{k:22s} {1e3*T[k]/n:7.3f} ms/eval  {C[k]/n:6.1f} calls/eval")
