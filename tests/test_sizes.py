"""Small rooms (issue 23 §5): no source file in src/ over 800 lines and no function over 120 lines. The rooms that
are still bigger are listed here with their size today and the reason; a new big file or function fails, and so
does a listed one that grows (split it, or raise its ceiling here with a reason)."""
import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "robodesign"
MAX_FILE_LINES = 800
MAX_FUNCTION_LINES = 120

#: file (relative to src/robodesign) → (its lines today, why it is still that big)
BIG_FILES = {
    "experiment/config.py": (853, "the config file's pydantic models and their resolution into problems; to split"),
    "formats/tolerance.py": (1000, "rotation maths, projections and ToleratedPose together (issue 23 §2 moves the "
                                   "rotation maths to core/spatial); +13: the plain tolerances' fast values"),
    "formats/urdf.py": (816, "URDF import and export of module sets and robots"),
    "solvers/ik.py": (992, "the IK loop with its own projection terms (issue 23 §2: they move to ToleratedPose); "
                           "+7 for whole turns (issue 21)"),
    "solvers/timing.py": (932, "trajectory type, limits and bounds, TOPP-RA and ruckig (issue 23 §5 lists the split)"),
}
#: "file:function" → (its lines today, why)
BIG_FUNCTIONS = {
    "cli/entry.py:build_parser": (149, "the argparse tree of every command, read top to bottom"),
    "judge/arc_torques.py:certify_arc_torques": (143, "the torque certification between samples: whole steps, "
                                                       "then pieces, then the cap (merged beside this test)"),
    "formats/urdf.py:export_urdf": (132, "writes the URDF document in document order"),
    "formats/urdf.py:import_urdf": (218, "reads the URDF document in document order"),
    "model/robot.py:_build": (149, "the pinocchio model and coal geometry of an assembly in one pass"),
    "solvers/ik.py:_make_term": (156, "one closure per tolerance projection (to move to ToleratedPose, issue 23 §2)"),
    "solvers/ik.py:solve_ik": (188, "the restart loop with its screening, sampling and acceptance (+7: whole turns)"),
    "solvers/trajopt.py:optimize_trajectory": (160, "the CasADi transcription: variables, dynamics, limits, objective"),
    "viewer/scene.py:build_scene": (152, "the scene in one pass: nodes, animation, paths, goals, bounds"),
}


def _sizes():
    files, functions = {}, {}
    for f in sorted(SRC.rglob("*.py")):
        rel = f.relative_to(SRC).as_posix()
        text = f.read_text(encoding="utf-8")
        files[rel] = len(text.splitlines())
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                key = f"{rel}:{node.name}"
                functions[key] = max(functions.get(key, 0), node.end_lineno - node.lineno + 1)
    return files, functions


def _over(sizes, limit, allowed):
    out = []
    for name, n in sizes.items():
        ceiling = allowed.get(name, (limit, ""))[0]
        if n > max(limit, ceiling):
            out.append(f"{name}: {n} lines (limit {max(limit, ceiling)})")
    return out


def test_no_big_file_or_function_beyond_the_listed_ones():
    files, functions = _sizes()
    assert _over(files, MAX_FILE_LINES, BIG_FILES) == []
    assert _over(functions, MAX_FUNCTION_LINES, BIG_FUNCTIONS) == []


def test_the_list_of_big_rooms_is_current():
    """Every listed exception still exists and is still over the limit (a room that was split leaves the list)."""
    files, functions = _sizes()
    assert [f for f in BIG_FILES if files.get(f, 0) <= MAX_FILE_LINES] == []
    assert [f for f in BIG_FUNCTIONS if functions.get(f, 0) <= MAX_FUNCTION_LINES] == []
    assert all(reason for _, reason in list(BIG_FILES.values()) + list(BIG_FUNCTIONS.values()))


def test_the_size_rules_catch_a_new_big_room():
    """The check itself: a file or function one line over its limit is reported, one at it is not."""
    assert _over({"a.py": 801, "b.py": 800}, MAX_FILE_LINES, {}) == ["a.py: 801 lines (limit 800)"]
    assert _over({"x.py:f": 150}, MAX_FUNCTION_LINES, {"x.py:f": (149, "r")}) == ["x.py:f: 150 lines (limit 149)"]
    assert _over({"x.py:f": 149}, MAX_FUNCTION_LINES, {"x.py:f": (149, "r")}) == []
