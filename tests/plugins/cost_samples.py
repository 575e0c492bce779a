"""A cost term from outside robodesign, for tests: ``samples`` = the number of time steps of the trajectory
(len(t) − 1). Importing this module registers nothing: the test registers the term at run time, in the
driver only, to show that worker processes learn it from the cost they are sent. Each evaluation appends
the evaluating process's id to the file named by ``RD_COST_LOG`` (if set)."""
import os


def samples(ctx) -> float:
    log = os.environ.get("RD_COST_LOG")
    if log:
        with open(log, "a") as f:
            f.write(f"{os.getpid()}\n")
    return float(len(ctx.t) - 1)
