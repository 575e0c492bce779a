import sys, json, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
from profile_evaluator import SHARED
from robodesign.formats.solution import Solution
from robodesign.formats.task_io import load_task
from robodesign.formats.module_io import load_module_set
from robodesign.judge.checker import check
import robodesign.formats.solution as S
task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
ms = load_module_set(SHARED / "modules" / "IMPROV")
sols = [S.parse_solution(s, "sol.json") for s in json.load(open("/tmp/s10/ptp3_sols.json"))]
# warm-up: one check of the first (kernels, meshes), then each solution once (each a new assembly)
check(task, sols[0], ms)
ts = []
for s in sols[1:]:
    t = time.process_time(); v = check(task, s, ms); ts.append(time.process_time() - t)
    assert v.valid
print(json.dumps([round(x * 1e3, 3) for x in ts]))
