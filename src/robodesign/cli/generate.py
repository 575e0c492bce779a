"""``robodesign generate FAMILY --out DIR --count N --seed S [family options]``, ``--list``, ``--from TASK``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List

from robodesign.core.errors import InputError
from robodesign.generate.registry import families, generate, get_family, regenerate


def add_generate_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("family", nargs="?", help="generator family (see --list)")
    p.add_argument("--list", action="store_true", help="list the families, their versions and options")
    p.add_argument("--out", help="output folder (task files <ID>.json, meshes in assets/)")
    p.add_argument("--count", type=int, default=1, help="number of tasks (index 0..N-1; default 1)")
    p.add_argument("--seed", type=int, default=0, help="folder seed (default 0)")
    p.add_argument("--from", dest="from_task", metavar="TASK",
                   help="regenerate this generated task file from the provenance in its header (into --out)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors (default: one line per task)")
    g.add_argument("--verbose", "-v", action="store_true", help="also print the family options used")
    seen: Dict[str, List[str]] = {}
    for fam in families().values():
        for o in fam.options:
            seen.setdefault(o.name, []).append(fam.name)
    for name, fams in seen.items():
        opt = next(o for f in families().values() for o in f.options if o.name == name)
        p.add_argument("--" + name.replace("_", "-"), dest="opt_" + name, default=None, metavar="VALUE",
                       help=f"[{', '.join(fams)}] {opt.help}{_default(opt)}")


def _default(o) -> str:
    return "" if o.default is None else f" (default {o.default})"


def cmd_generate(args) -> int:
    if args.list:
        for fam in families().values():
            print(f"{fam.name}  (version {fam.version})  {fam.summary}")
            for o in fam.options:
                ch = f" {{{'|'.join(o.choices)}}}" if o.choices else ""
                print(f"    --{o.name.replace('_', '-')}{ch}  {o.help}{_default(o)}")
        return 0
    given = {k[4:]: v for k, v in vars(args).items() if k.startswith("opt_") and v is not None}
    if args.from_task:
        if args.family or given:
            raise InputError("--from takes the family and its options from the task's header: give no others")
        if not args.out:
            raise InputError("--out is required")
        print(regenerate(Path(args.from_task), Path(args.out)))
        return 0
    if not args.family:
        raise InputError("name a family (robodesign generate --list shows them)")
    if not args.out:
        raise InputError("--out is required")
    get_family(args.family)
    if args.verbose:
        print(f"{args.family}: seed {args.seed}, {args.count} task(s), options "
              f"{', '.join(f'{k}={v}' for k, v in given.items()) or '(defaults)'}", flush=True)
    files = generate(args.family, Path(args.out), args.count, args.seed, given,
                     progress=None if args.quiet else (lambda p: print(p, flush=True)))
    if not args.quiet:
        print(f"robodesign: wrote {len(files)} {args.family} task(s) to {args.out}", file=sys.stderr)
    return 0
