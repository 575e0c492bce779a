"""`robodesign serve` freezes what its process holds at start-up out of the cyclic garbage collector's full
passes: with the libraries and the seeded site loaded, one full pass scanned ~130,000 objects (88–193 ms under
load, a page-latency spike each time; docs/benchmarks.md "Website under siege"). An app built elsewhere (a test
with TestClient) freezes nothing. Functional checks, no timing."""
import gc

import uvicorn
from fastapi.testclient import TestClient

from robodesign.web import server
from robodesign.web.app import create_app


def test_freezing_takes_the_start_up_objects_out_of_full_passes(tmp_path):
    gc.unfreeze()
    create_app(data_dir=tmp_path / "data", seed_builtin=False)
    try:
        frozen = server.freeze_startup_objects()
        assert frozen == gc.get_freeze_count() > 10_000  # the interpreter, the libraries and the site
        assert len(gc.get_objects(generation=2)) < frozen  # a full pass no longer looks at them
    finally:
        gc.unfreeze()


def test_serve_freezes_before_it_serves(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(server, "freeze_startup_objects", lambda: calls.append("freeze"))
    monkeypatch.setattr(server, "raise_fd_limit", lambda *a, **k: None)
    monkeypatch.setattr(server, "install_log_limits", lambda *a, **k: None)
    monkeypatch.setattr(uvicorn.Config, "load", lambda self: None)  # keeps the test process's logging as it is
    monkeypatch.setattr(uvicorn.Server, "run", lambda self: calls.append("run"))
    server.serve(create_app(data_dir=tmp_path / "data", seed_builtin=False), "127.0.0.1", 0)
    assert calls == ["freeze", "run"]


def test_an_app_in_a_test_process_freezes_nothing(tmp_path):
    gc.unfreeze()
    with TestClient(create_app(data_dir=tmp_path / "data", seed_builtin=False)) as c:
        assert c.get("/healthz").status_code == 200
        assert gc.get_freeze_count() == 0
