"""The CoBRA benchmark website: ``create_app(db_url, data_dir)`` (FastAPI + SQLAlchemy). See docs/website.md."""
from robodesign.web.app import create_app

__all__ = ["create_app"]
