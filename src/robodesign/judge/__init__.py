"""The judge: what a trajectory does on a robot (``TrajectoryQuantities``) and the checker's verdict."""
