"""The on-disk numba cache of a module's compiled kernels: its readiness stamp and its background compiler.

A module with numba kernels (``solvers.ik_kernel``, ``judge.interval_kernel``, ``model.geometry_kernel``,
``model.sweep_kernel``) never stalls a command on their compilation: with a cold cache it starts
``python -m <module>`` in the background (niced, its own process group) and runs its numpy/Python path meanwhile;
the compiler writes a stamp beside numba's cache files once every kernel is there, so a later process loads them
instead. The stamp names numba, Python, the CPU and the source file's size and time: any change means a new
compilation. :class:`KernelCache` is the cache and its stamp; :class:`KernelModule` the readiness the modules
share (``available``, ``ready``, ``warm_up``, the background compiler's entry point).
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, cast

try:
    from numba import njit
    NUMBA_IMPORTED = True
except Exception:  # pragma: no cover - numba is a dependency; without it the kernels' modules run plain Python
    NUMBA_IMPORTED = False

    def njit(*args, **kwargs):  # type: ignore[no-redef]  # the stand-in for numba's decorator
        return (lambda f: f) if not args or not callable(args[0]) else args[0]

__all__ = ["KernelCache", "KernelModule", "NUMBA_IMPORTED", "background_compile", "njit"]


class KernelCache:
    """The cache of the kernels ``kernels`` of module ``module`` (its file ``source``); ``dispatcher`` is one
    of its numba dispatchers (numba keeps one cache folder per module)."""

    def __init__(self, module: str, source: str, dispatcher: Any, kernels: Sequence[str]) -> None:
        self.module, self.source, self.dispatcher, self.kernels = module, Path(source), dispatcher, tuple(kernels)

    def cache_dir(self) -> Path:
        """Where numba caches the module's kernels (``__pycache__`` beside it, ``NUMBA_CACHE_DIR`` or numba's
        user-wide fall-back)."""
        return Path(cast(Any, self.dispatcher)._cache._cache_path)   # numba's dispatcher; its stubs omit it

    def stamp_path(self) -> Path:
        return self.cache_dir() / f"robodesign_{self.source.stem}.ready"

    def stamp_text(self) -> str:
        import platform

        import numba
        from llvmlite import binding
        src = self.source.stat()
        # the resolved executable: `python` and `python3` of one environment are the same interpreter
        return (f"numba {numba.__version__}; python {sys.version.split()[0]} {Path(sys.executable).resolve()}; "
                f"cpu {platform.machine()} {binding.get_host_cpu_name()}; source {src.st_size} {src.st_mtime_ns}")

    def compiled(self) -> bool:
        """True when the cache holds every kernel for this numba, Python, CPU and source."""
        try:
            stamp = self.stamp_path()
            if stamp.read_text() != self.stamp_text():
                return False
            return all(any(stamp.parent.glob(f"{self.source.stem}.{k}-*.nbi")) for k in self.kernels)
        except (OSError, AttributeError):
            return False

    def start_compiler(self) -> Optional[subprocess.Popen]:
        """``python -m <module>`` in the background (what :func:`background_compile` does there), or None."""
        env = dict(os.environ)
        src_root = str(self.source.resolve().parents[2])   # the folder holding the robodesign package
        env["PYTHONPATH"] = src_root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        # its own process group (Ctrl-C on the command does not stop it: it finishes the cache even if the
        # command ends first) but the command's session: Linux shares the CPU between sessions (autogroup), so a
        # session of its own would take a whole share from a busy machine, while inside the command's session its
        # nice value leaves the CPU to the command
        group = {"process_group": 0} if sys.version_info >= (3, 11) else {"preexec_fn": os.setpgrp}
        try:
            return subprocess.Popen([sys.executable, "-m", self.module], env=env, stdin=subprocess.DEVNULL,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, **group)
        except OSError:
            return None

    def compile_into_cache(self, warm_up: Callable[[], Any]) -> int:
        """Compile every kernel (``warm_up`` calls each) into numba's cache and write the stamp, once, under a
        lock shared with concurrent compilers."""
        import fcntl
        stamp = self.stamp_path()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        with open(stamp.with_suffix(".lock"), "a+") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not self.compiled():
                warm_up()
                tmp = stamp.with_suffix(f".tmp{os.getpid()}")
                tmp.write_text(self.stamp_text())
                tmp.replace(stamp)
        return 0


def background_compile(available: bool, compile_into_cache: Callable[[], int]) -> int:
    """What ``python -m <module>`` runs: niced (``ROBODESIGN_COMPILE_NICE``, default 10: the commands that wait
    for nothing come first), then the compilation; 1 without numba."""
    try:
        os.nice(int(os.environ.get("ROBODESIGN_COMPILE_NICE", "10")))
    except (OSError, ValueError):
        pass
    return compile_into_cache() if available else 1


class KernelModule:
    """The readiness of one module's compiled kernels (``judge.interval_kernel``, ``model.geometry_kernel``,
    ``model.sweep_kernel``): :meth:`available` (numba imports and ``ROBODESIGN_JIT`` is not 0), :meth:`ready`
    (compiled in this process; with a cold cache the background compilation starts once and the module's
    numpy/Python path runs until a later call finds the stamp, looked for at most every ``every`` seconds),
    :meth:`warm_up` (compile or load them now: ``warm`` calls each kernel), :meth:`compile_into_cache` and
    :meth:`main` (what ``python -m <module>`` runs). Both paths of a module give the same results."""

    def __init__(self, module: str, source: str, dispatcher: Any, kernels: Sequence[str], warm: Callable[[], Any],
                 every: float = 0.0) -> None:
        self.cache = KernelCache(module, source, dispatcher, kernels)
        self.warm, self.every = warm, float(every)
        self.state: Optional[str] = None  # None (not decided) | "plain" (compiling elsewhere) | "ready" | "failed"
        self.looked = -math.inf           # time.monotonic() of the last look for the stamp

    def available(self) -> bool:
        """True when numba imports and ``ROBODESIGN_JIT`` is not ``0``."""
        return NUMBA_IMPORTED and os.environ.get("ROBODESIGN_JIT", "1").strip().lower() not in ("0", "false", "no",
                                                                                                "off")

    def compiled(self) -> bool:
        """True when the cache holds every kernel for this numba, Python, CPU and source."""
        return self.cache.compiled()

    def warm_up(self) -> bool:
        """Compile (or load) the kernels in this process now; False when numba is unavailable."""
        if not self.available():
            return False
        self.warm()
        self.state = "ready"
        return True

    def ready(self) -> bool:
        """True when the compiled kernels run in this process (``ROBODESIGN_JIT=wait``: compiled here at the
        first call)."""
        if self.state == "ready" or not self.available():
            return self.state == "ready"
        now = time.monotonic()
        if self.state is not None and now - self.looked < self.every:
            return False
        self.looked = now
        if self.compiled():
            self.warm_up()
        elif os.environ.get("ROBODESIGN_JIT", "").strip().lower() == "wait":
            self.compile_into_cache()
            self.warm_up()
        elif self.state is None:
            self.state = "plain" if self.cache.start_compiler() is not None else "failed"
        return self.state == "ready"

    def compile_into_cache(self) -> int:
        """Compile the kernels into numba's cache and write the stamp (under a lock shared with concurrent
        compilers)."""
        return self.cache.compile_into_cache(self.warm_up)

    def main(self) -> int:
        """``python -m <module>``: the background compilation (niced)."""
        return background_compile(self.available(), self.compile_into_cache)
