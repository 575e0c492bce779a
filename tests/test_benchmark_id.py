import pytest

from robodesign.formats.benchmark_id import BenchmarkID, RobotRef, resolve
from robodesign.formats.costs import parse_cost
from robodesign.core.errors import InputError


def test_simple_id():
    b = BenchmarkID.parse("IMPROV:cyc:simple/PTP_1")
    assert b.robot.robots == (RobotRef("IMPROV"),)
    assert b.robot.robots[0].kind == "module_set" and not b.is_collaborative
    assert b.cost.terms == (("cyc", 1.0),)
    assert b.task == "simple/PTP_1"
    assert str(b) == "IMPROV:cyc:simple/PTP_1"


def test_cost_part_in_both_notations_and_compounds():
    a = BenchmarkID.parse("IMPROV:[(cyc|0.2),(mechEnergy|1)]:simple/PTP_2")
    b = BenchmarkID.parse("IMPROV:cyc_0.2,mechEnergy:simple/PTP_2")
    c = BenchmarkID.parse("IMPROV:Liu2:simple/PTP_2")
    assert a == b == c
    assert str(a) == "IMPROV:cyc_0.2,mechEnergy:simple/PTP_2"
    assert str(c) == "IMPROV:Liu2:simple/PTP_2"                    # the compound name is kept
    assert BenchmarkID.parse(str(a)) == a and BenchmarkID.parse(str(c)) == c


def test_prefixes_and_collaborative_list():
    b = BenchmarkID.parse("M-geometric_primitive_modules:Whit2:Liu/PTP_3")
    assert b.robot.robots == (RobotRef("geometric_primitive_modules", "M-"),)
    assert b.robot.robots[0].kind == "module_set"
    assert BenchmarkID.parse("C-myArm:cyc:a").robot.robots[0].kind == "fixed"
    assert BenchmarkID.parse("IND-panda:cyc:a").robot.robots[0] == RobotRef("panda", "IND-")
    b = BenchmarkID.parse("[M-IMPROV, C-panda]:fulfillN_-1:deep/name/space/T.1")
    assert b.is_collaborative
    assert [str(r) for r in b.robot.robots] == ["M-IMPROV", "C-panda"]
    assert b.task == "deep/name/space/T.1"
    assert str(b) == "[M-IMPROV,C-panda]:fulfillN_-1.0:deep/name/space/T.1"
    assert BenchmarkID.parse(str(b)) == b


@pytest.mark.parametrize("text, message", [
    ("IMPROV:cyc", r"expected three parts Robot:Cost:Task separated by ':', found 2"),
    ("IMPROV:cyc:simple/PTP_1:x", r"found 4 part"),
    ("IMPROV::simple/PTP_1", r"the cost part is empty"),
    (":cyc:simple/PTP_1", r"the robot part is empty"),
    ("IMPROV:cyc:", r"the task part is empty"),
    ("IMPROV:cyc:/simple/PTP_1", r"empty path segment"),
    ("IMPROV:cyc:simple//PTP_1", r"empty path segment"),
    ("IMPROV:cyc:../etc", r"invalid task ID"),
    ("IMPROV:cyc:simple/PTP 1", r"invalid task ID"),
    ("IMPROV:cyx:simple/PTP_1", r"cost part: unknown cost 'cyx' \(did you mean 'cyc'\?\); known costs: cyc"),
    ("IMPROV:cyc_x:simple/PTP_1", r"cost part: weight 'x' of cost 'cyc' is not a number"),
    ("IMP ROV:cyc:simple/PTP_1", r"invalid robot name 'IMP ROV'"),
    ("M-:cyc:simple/PTP_1", r"robot 'M-' has a prefix but no name"),
    ("A,B:cyc:simple/PTP_1", r"several robots must be written as a list \[R1,R2\]"),
    ("[A,B:cyc:simple/PTP_1", r"does not end with '\]'"),
    ("[]:cyc:simple/PTP_1", r"the robot list is empty"),
])
def test_bad_ids(text, message):
    with pytest.raises(InputError, match=r"run\.toml: benchmark: benchmark ID .*" + message):
        BenchmarkID.parse(text, file="run.toml", path="benchmark")


def test_non_string():
    with pytest.raises(InputError, match="expected a benchmark ID string"):
        BenchmarkID.parse(None)


def test_resolve_with_lookups():
    sets = {"IMPROV": "<IMPROV db>", "panda": "<panda db>"}
    tasks = {"simple/PTP_1": "<task PTP_1>"}
    r = resolve("IMPROV:Liu2:simple/PTP_1", sets.__getitem__, tasks.__getitem__)
    assert r.robot == "<IMPROV db>" and r.task == "<task PTP_1>"
    assert r.cost == parse_cost("mechEnergy,cyc_0.2")
    r = BenchmarkID.parse("[IMPROV,C-panda]:cyc:simple/PTP_1").resolve(sets.get, tasks.get)
    assert r.robot == ("<IMPROV db>", "<panda db>")
    # without lookups the names come back
    assert resolve("M-IMPROV:cyc:simple/PTP_1") == ("IMPROV", parse_cost("cyc"), "simple/PTP_1")


def test_resolve_unknown_parts():
    sets = {"IMPROV": object()}
    with pytest.raises(InputError, match=r"benchmark ID 'PROMODULAR:cyc:simple/PTP_1': unknown module set "
                                         r"'PROMODULAR'"):
        resolve("PROMODULAR:cyc:simple/PTP_1", sets.__getitem__)
    with pytest.raises(InputError, match=r"unknown robot 'ur5'"):
        resolve("C-ur5:cyc:simple/PTP_1", sets.get)
    with pytest.raises(InputError, match=r"unknown task 'simple/PTP_9'"):
        resolve("IMPROV:cyc:simple/PTP_9", sets.__getitem__, {}.__getitem__)


def test_collaborative_cost_list_one_cost_per_robot():
    b = BenchmarkID.parse("[M-robodesign_arm,M-IMPROV]:[cyc,Liu2]:robodesign-collab/shared_conveyor")
    assert b.is_collaborative and [c.descriptor() for c in b.costs] == ["cyc", "cyc_0.2,mechEnergy"]
    assert str(b) == "[M-robodesign_arm,M-IMPROV]:[cyc,Liu2]:robodesign-collab/shared_conveyor"
    # a weighted sum inside the list in bracket notation; one cost for all robots
    b = BenchmarkID.parse("[A,B]:[[(cyc|0.2),(mechEnergy|1)],mass]:t/x")
    assert [c.descriptor() for c in b.costs] == ["cyc_0.2,mechEnergy", "mass"]
    b = BenchmarkID.parse("[A,B]:cyc:t/x")
    assert [c.descriptor() for c in b.costs] == ["cyc", "cyc"] and str(b) == "[A,B]:cyc:t/x"
    b = BenchmarkID.parse("[A,B]:[(cyc|0.2),(mechEnergy|1)]:t/x")  # the term notation: one cost for both
    assert [c.descriptor() for c in b.costs] == ["cyc_0.2,mechEnergy"] * 2
    assert BenchmarkID.parse("A:cyc:t/x").costs == ()
    with pytest.raises(InputError, match="3 costs for 2 robots"):
        BenchmarkID.parse("[A,B]:[cyc,mass,numJ]:t/x")
    with pytest.raises(InputError, match=r"cost of robot 2 \('nope'\)"):
        BenchmarkID.parse("[A,B]:[cyc,nope]:t/x")
