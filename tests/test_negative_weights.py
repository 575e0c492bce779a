"""A negative weight on a cost that is minimised (`cyc_-1`) is bad input everywhere: the parser, the CLI
(exit 2 naming the file and costFunction) and the website (rejected upload, no leaderboard). Rewards keep
the reference's negative weights (`fulfillN_-1`)."""
import json

import pytest

from robodesign.cli.entry import main

from test_checker import plan, solution, task_json
from conftest import toy_module_set

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from robodesign.web import create_app  # noqa: E402
from test_web import make_seed, upload  # noqa: E402


def toy_solution_json(cost):
    t, q, dq, ddq, g2t = plan()
    return solution(t, q, dq, ddq, g2t, cost=cost).to_json()


@pytest.mark.parametrize("cost, code", [("cyc_-1", 2), ("cyc,qDist_-0.01", 2), ("Liu2_-1", 2), ("cyc_1e999", 2),
                                        ("cyc,fulfillN_-1", 0), ("cyc", 0)])
def test_cli_check(tmp_path, capsys, cost, code):
    toy_module_set(tmp_path)
    (tmp_path / "toy" / "all.json").write_text(json.dumps(task_json()))
    f = tmp_path / "sol.json"
    f.write_text(json.dumps(toy_solution_json(cost)))
    got = main(["check", str(tmp_path / "toy" / "all.json"), str(f), "--modules", str(tmp_path / "toy")])
    err = capsys.readouterr().err
    assert got == code, err
    if code == 2:
        assert f"{f}: costFunction:" in err and ("negative" in err or "finite" in err)


def test_website_rejects_a_negative_weight(tmp_path):
    seed = make_seed(tmp_path / "seed")
    app = create_app(data_dir=tmp_path / "data", seed=[seed], seed_builtin=False)
    with TestClient(app) as c:
        r = upload(c, toy_solution_json("cyc_-1"))
        assert 400 <= r.status_code < 500, r.text
        assert "negative" in r.text and "costFunction" in r.text
        assert "cyc_-1" not in c.get("/").text  # no leaderboard for it
        r = upload(c, toy_solution_json("cyc"))
        assert r.status_code == 201, r.text
