"""The site freezes what it holds at start-up out of the cyclic garbage collector's full passes: with the
libraries and the seeded site loaded, one full pass scans ~130,000 objects (tens of milliseconds, a page
latency spike each time it runs; docs/benchmarks.md "Website under siege"). Functional check, no timing."""
import gc

from fastapi.testclient import TestClient

from robodesign.web.app import create_app


def test_startup_freezes_the_long_lived_objects(tmp_path):
    gc.unfreeze()
    assert gc.get_freeze_count() == 0
    app = create_app(data_dir=tmp_path / "data", seed_builtin=False)
    try:
        with TestClient(app) as c:
            frozen = gc.get_freeze_count()
            assert frozen > 10_000  # the interpreter, the libraries and the site
            assert c.get("/healthz").status_code == 200
            # a full pass no longer looks at them: it sees far fewer objects than were frozen
            assert len(gc.get_objects(generation=2)) < frozen
    finally:
        gc.unfreeze()
