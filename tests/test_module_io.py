"""Module-set loading: real files load; every kind of bad input names the file and the field."""
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from robodesign import InputError, load_module_set
from robodesign.formats.module_io import module_set_to_json, write_module_set

from conftest import IMPROV, PRIMITIVES


def test_real_sets_load_with_their_contents():
    ms = load_module_set(IMPROV)
    assert ms.name == "IMPROV" and ms.ignore_collisions == "rigid_via_joint"
    pb21 = ms["21"]
    assert pb21.dof == 2 and [b.id for b in pb21.bodies] == ["21_body_1", "21_body_2", "21_body_3"]
    j = pb21.joints[0]
    assert (j.limits.lower, j.limits.upper, j.limits.torque, j.limits.velocity, j.limits.acceleration) == \
        (-2.9671, 2.9671, 75.504, 1.2566, 2.618)
    assert (j.gear_ratio, j.motor_inertia, j.friction_coulomb, j.friction_viscous) == (160.0, 5.23e-05, 7.14, 15.68)
    base = ms["1"].connectors[0]
    assert base.type == "base" and base.gender == "f" and base.size == ()
    # L3 collision is a .wrl convex decomposition with 4 parts
    from robodesign.formats.geometry import coal_shapes
    g = ms["12"].bodies[0].collision[0]
    assert g.kind == "mesh" and g.file.name == "L3.stl.wrl" and len(coal_shapes(g)) == 4
    prim = load_module_set(PRIMITIVES)
    assert prim.ignore_collisions == "via_joint"  # the default
    # the Infinity literal is read as +inf
    assert any(np.isinf(j.limits.torque) for m in prim for j in m.joints)


def test_builtin_set_by_name_and_roundtrip(tmp_path):
    ms = load_module_set("robodesign_arm")
    assert len(ms) >= 10 and ms.of_kind("base") and ms.of_kind("eef") and ms.of_kind("joint")
    out = write_module_set(ms, tmp_path / "copy")
    # mesh references are re-written relative to the original folder: copy the meshes along
    if (ms.root / "meshes").is_dir():
        shutil.copytree(ms.root / "meshes", tmp_path / "copy" / "meshes")
    back = load_module_set(out.parent)
    assert module_set_to_json(back) == module_set_to_json(ms)


def _broken(tmp_path: Path, mutate) -> Path:
    """A copy of IMPROV's modules.json (meshes copied too) with one mutation."""
    d = tmp_path / "IMPROV"
    shutil.copytree(IMPROV, d)
    data = json.loads((d / "modules.json").read_text())
    mutate(data)
    (d / "modules.json").write_text(json.dumps(data))
    return d


CASES = [
    ("bad number", lambda d: d["modules"][7]["joints"][0]["limits"].__setitem__("positionLower", "abc"),
     'IMPROV/modules.json: modules[7].joints[0].limits.positionLower: expected a number, got "abc"'),
    ("duplicate id", lambda d: d["modules"][1]["header"].__setitem__("ID", "1"),
     "IMPROV/modules.json: modules[1].header.ID: duplicate module ID '1'"),
    ("unknown body", lambda d: d["modules"][7]["joints"][0].__setitem__("parent", "nobody"),
     "IMPROV/modules.json: modules[7].joints[0].parent: joint '21_joint_1' references unknown body 'nobody'"),
    ("escape", lambda d: d["modules"][1]["bodies"][0]["collision"][0]["parameters"].__setitem__("file", "../../x.stl"),
     "IMPROV/modules.json: modules[1].bodies[0].collision[0].parameters.file: file reference '../../x.stl' escapes"),
    ("absolute", lambda d: d["modules"][1]["bodies"][0]["collision"][0]["parameters"].__setitem__("file", "/etc/passwd"),
     "IMPROV/modules.json: modules[1].bodies[0].collision[0].parameters.file: absolute file paths are not allowed"),
    ("missing mesh", lambda d: d["modules"][1]["bodies"][0]["collision"][0]["parameters"].__setitem__("file", "STLfiles/no.stl"),
     "IMPROV/modules.json: modules[1].bodies[0].collision[0].parameters.file: mesh file not found: 'STLfiles/no.stl'"),
    ("unknown key", lambda d: d["modules"][2]["bodies"][0].__setitem__("colour", "red"),
     "IMPROV/modules.json: modules[2].bodies[0]: unknown key(s): 'colour'"),
    ("negative mass", lambda d: d["modules"][2]["bodies"][0].__setitem__("mass", -1.0),
     "IMPROV/modules.json: modules[2].bodies[0].mass"),
    ("lower > upper", lambda d: d["modules"][7]["joints"][0]["limits"].__setitem__("positionLower", 4.0),
     "IMPROV/modules.json: modules[7].joints[0].limits.positionLower: positionLower 4.0 > positionUpper 2.9671"),
    ("duplicate connector", lambda d: d["modules"][1]["bodies"][0]["connectors"][1].__setitem__("ID", "101_distal_connector"),
     "IMPROV/modules.json: modules[1].bodies[0].connectors[1].ID: duplicate connector ID '101_distal_connector'"),
    ("bad pose", lambda d: d["modules"][1]["bodies"][0]["connectors"][0].__setitem__("pose", [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
     "IMPROV/modules.json: modules[1].bodies[0].connectors[0].pose: rotation part is not a proper rotation matrix"),
]


@pytest.mark.parametrize("name,mutate,message", CASES, ids=[c[0] for c in CASES])
def test_bad_module_files_name_file_and_field(tmp_path, name, mutate, message):
    d = _broken(tmp_path, mutate)
    with pytest.raises(InputError) as e:
        load_module_set(d, use_cache=False)
    assert str(e.value).startswith(message), str(e.value)


def test_malformed_json_and_nan_and_missing(tmp_path):
    d = tmp_path / "bad"
    d.mkdir()
    (d / "modules.json").write_text('{"modules": [ {"header": ')
    with pytest.raises(InputError, match=r"bad/modules.json: malformed JSON at line 1, column 26: Expecting value"):
        load_module_set(d)
    (d / "modules.json").write_text(json.dumps({"modules": []}).replace("[]", '[{"header": {"ID": "1", "name": "x"}, "bodies": [{"ID": "b", "mass": NaN}]}]'))
    with pytest.raises(InputError, match=r"bad/modules.json: modules\[0\].bodies\[0\].mass: NaN is not a valid value"):
        load_module_set(d, use_cache=False)
    with pytest.raises(InputError, match="no such module set"):
        load_module_set(tmp_path / "nothing")
