"""A benchmark site's settings (data folder, database, request and zip caps, checker workers, seeding) and the
per-upload limits (docs/website.md, "Limits")."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence

MiB = 1 << 20


@dataclass
class Limits:
    """What one uploaded solution may hold (docs/website.md, "Limits"). Beyond them: 413 naming the field."""
    notes_chars: int = 16_384  # ``notes``
    text_chars: int = 1_000  # every other free-text field: version, publication, processorName, date, list entries
    list_items: int = 100  # entries of author / email / affiliation / tags
    trajectory_values: int = 500_000  # samples × joints of the trajectory (of all robots together)
    modules: int = 1_000  # entries of moduleOrder / moduleConnection
    robots: int = 16  # robots of a collaborative task or solution
    robot_id_chars: int = 100  # a robot's ID in a collaborative task


@dataclass
class Settings:
    data_dir: Path
    db_url: Optional[str] = None
    max_request_bytes: int = 20 * MiB
    max_unzipped_bytes: int = 200 * MiB
    max_zip_entries: int = 5000
    check_workers: int = max(2, min(8, os.cpu_count() or 2))
    seed_dirs: Sequence[Path] = ()
    seed_builtin: bool = True
    limits: Limits = field(default_factory=Limits)
