"""What a task-generator family is: its options, its output and its description (no family imports this
package's registry, so the registry can import every family at module level without a cycle)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Tuple

from robodesign.core.errors import InputError
from robodesign.generate.common import Provenance, task_text


@dataclass(frozen=True)
class Option:
    name: str  # CLI spelling without dashes, e.g. "goals" (→ --goals)
    kind: type  # int | float | str
    default: object
    help: str
    choices: Optional[Tuple[str, ...]] = None
    minimum: Optional[float] = None
    path: bool = False  # a file given by the user (copied into the output folder)

    def parse(self, value, family: str) -> object:
        where = f"{family} --{self.name.replace('_', '-')}"
        if self.kind is str:
            v = str(value)
            if self.choices and v not in self.choices:
                raise InputError(f"{where}: expected one of {', '.join(self.choices)}, got {v!r}")
            return v
        try:
            v = self.kind(value)
        except (TypeError, ValueError):
            raise InputError(f"{where}: expected {'an integer' if self.kind is int else 'a number'}, got {value!r}") \
                from None
        if v != v or v in (float("inf"), float("-inf")):
            raise InputError(f"{where}: expected a finite number, got {value!r}")
        if self.minimum is not None and v < self.minimum:
            raise InputError(f"{where}: must be at least {self.minimum:g}, got {value!r}")
        return v


VARIANT = Option("variant", str, "published",
                 "published: the distributions of the published task files (tolerances, full-pose goals, goal "
                 "distances and heights, base freedom, constraint lists, obstacle layouts; docs/generators.md); "
                 "easy: the earlier robodesign variant (±5 mm, orientation free, goals checked with the "
                 "robodesign_arm reference design, see --verify)", choices=("published", "easy"))

VERIFY = Option("verify", str, None,
                "only with --variant easy (default solve there): solve: the reference design (robodesign_arm, "
                "default order) must solve the whole task and pass the checker; ik: every goal needs a "
                "collision-free, torque-feasible IK solution of it", choices=("solve", "ik"))


def verify_mode(opts: Dict[str, Any]) -> str:
    """The easy variant's ``--verify`` (solve unless given)."""
    return str(opts.get("verify") or "solve")


def check_variant_options(family: str, opts: Dict[str, Any]) -> None:
    if opts.get("variant") != "easy" and opts.get("verify") is not None:
        raise InputError(f"{family} --verify: only with --variant easy (the published variant keeps a task by the "
                         f"published rule and a geometric reachability bound, never by robodesign's own designs)")


@dataclass
class GeneratedTask:
    task_id: str
    task: dict  # JSON-ready task (assets such as meshes are written by the family's build into <out>/assets/)

    @property
    def text(self) -> str:
        return task_text(self.task)

    @property
    def filename(self) -> str:
        return self.task_id + ".json"


@dataclass(frozen=True)
class Family:
    name: str
    version: int
    summary: str
    options: Tuple[Option, ...]
    build: Callable[[Provenance, Dict[str, Any], Path], GeneratedTask]

    def option(self, name: str) -> Option:
        for o in self.options:
            if o.name == name:
                return o
        raise InputError(f"{self.name} has no option --{name.replace('_', '-')} "
                         f"(its options: {', '.join('--' + o.name.replace('_', '-') for o in self.options) or 'none'})")

    def resolve(self, given: Dict[str, Any]) -> Dict[str, Any]:
        """Typed values of every option (defaults filled in); unknown options are an error."""
        for k in given:
            self.option(k)
        values = {o.name: o.parse(given[o.name], self.name) if given.get(o.name) is not None else o.default
                  for o in self.options}
        check_variant_options(self.name, values)
        return values


def copy_file(src: Path) -> bytes:
    """The bytes of a user-given file (a clear error when it is missing)."""
    src = Path(src)
    if not src.is_file():
        raise InputError("no such file", file=str(src))
    return src.read_bytes()


__all__ = ["Family", "GeneratedTask", "Option", "VARIANT", "VERIFY", "check_variant_options", "copy_file",
           "verify_mode"]
