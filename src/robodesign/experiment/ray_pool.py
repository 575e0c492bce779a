"""The Ray executor: evaluator actors on a local Ray instance or a cluster, fed in chunks like the process pool
(:class:`~robodesign.experiment.pools.ChunkedPool`; faults and interrupts as the executors module says). Apart
from the other executors because Ray is optional and its actor bookkeeping is its own."""
from __future__ import annotations

import logging
import os
import time
from concurrent.futures import Future
from typing import Dict, List, Optional

from robodesign.core.errors import InputError
from robodesign.core.gc_heap import freeze_worker_heap
from robodesign.design.evaluator import Evaluation, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.experiment.pools import ChunkedPool, _Chunk, build_evaluators, ignore_sigint, sigint_ignored
from robodesign.solvers import ik_kernel


def ray_env() -> None:
    """Environment every robodesign Ray driver sets (docs/ray.md)."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")


class EvaluatorActor:
    """A Ray actor holding the evaluators of an experiment (built once, in ``__init__``). ``jit``: the IK
    loop the driver runs (:func:`robodesign.solvers.ik_kernel.ready`): False, the Python loop; True, the
    compiled one, compiled in the actor if its machine's cache is cold. An actor never decides alone, so
    evaluations do not depend on where they ran (the two loops agree to ~1e-15, not bit for bit)."""

    def __init__(self, specs: Dict[str, EvaluatorSpec], jit: Optional[bool] = None):
        ignore_sigint()
        if jit is not None:
            os.environ["ROBODESIGN_JIT"] = "wait" if jit else "0"
        self.evaluators = build_evaluators(specs)
        warm_up()  # as a process-pool worker: the first candidates cost what the others do
        freeze_worker_heap()

    def evaluate_chunk(self, spec_id: str, candidates: List[Candidate]) -> List[Evaluation]:
        ev = self.evaluators[spec_id]
        return [ev(c) for c in candidates]

    def pid(self) -> int:
        return os.getpid()

    def ik_loop(self) -> str:
        """"compiled" or "python": the IK loop this actor runs."""
        return "compiled" if ik_kernel.ready() else "python"


class RayPool(ChunkedPool):
    """Candidates are evaluated by ``workers`` Ray actors (one CPU each), in chunks (:class:`ChunkedPool`):
    a chunk goes to the actor with the fewest chunks in flight, at most two per actor (one running, one
    waiting), so the small chunks at the end of a batch go to the actors that get free first.

    ``address=None`` starts a private local Ray instance (``num_cpus=workers``, no dashboard, bound to
    127.0.0.1); otherwise it connects to the cluster at ``address`` (``HOST:PORT`` of ``ray start --head``)
    and defaults ``workers`` to the cluster's CPU count.
    """
    kind = "ray"
    worker_noun = "a Ray evaluator actor"

    def __init__(self, specs, workers: Optional[int] = None, address: Optional[str] = None,
                 max_restarts: int = 4, start_timeout: float = 300.0, chunk_size: Optional[int] = None):
        if chunk_size is not None and int(chunk_size) < 1:  # before Ray is started
            raise InputError(f"chunk size must be at least 1, got {chunk_size}")
        ray_env()
        import ray
        t0 = time.perf_counter()
        self._owns = False
        if not ray.is_initialized():
            with sigint_ignored():  # Ray's local processes leave Ctrl-C to the driver, as pool workers do
                self._init_ray(ray, address, workers)
            self._owns = True
        if not workers:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        super().__init__(specs, workers, chunk_size)
        self.address = address
        self.max_restarts = int(max_restarts)
        self.jit = ik_kernel.ready()  # the driver's IK loop, which every actor (a restarted one too) runs
        self._actor_cls = ray.remote(EvaluatorActor).options(num_cpus=1, max_restarts=self.max_restarts,
                                                              max_task_retries=-1)
        self.actors = [self._new_actor() for _ in range(self.workers)]
        self._calls: List[List[Future]] = [[] for _ in range(self.workers)]  # per actor: its chunks' futures
        try:
            self.pids = ray.get([a.pid.remote() for a in self.actors], timeout=start_timeout)
        except ray.exceptions.GetTimeoutError:
            cpus = ray.cluster_resources().get("CPU", 0)
            self.close()
            raise InputError(f"Ray could not start {self.workers} evaluator actors within {start_timeout:.0f} s "
                             f"(the cluster has {cpus:g} CPUs; use --workers)") from None
        self.startup_seconds = time.perf_counter() - t0

    @staticmethod
    def _init_ray(ray, address: Optional[str], workers: Optional[int]) -> None:
        if address:
            host = address.rsplit(":", 1)[0]
            # a cluster on this machine's loopback: the driver must present itself with the same
            # address, or Ray looks for a local node under the machine's external IP and fails
            local = host in ("127.0.0.1", "localhost") or host.startswith("127.")
            ray.init(address=address, logging_level=logging.WARNING, log_to_driver=True,
                     **({"_node_ip_address": "127.0.0.1"} if local else {}))
        else:
            ray.init(address="local", num_cpus=workers or max(1, os.cpu_count() or 1), include_dashboard=False,
                     _node_ip_address="127.0.0.1", logging_level=logging.WARNING, log_to_driver=True)

    def _new_actor(self):
        # the specs are small plain data, passed inline: a restarted actor never depends on the object store
        return self._actor_cls.remote(self.specs, self.jit)

    def _send(self, spec_id: str, chunk: _Chunk) -> None:
        for calls in self._calls:
            calls[:] = [f for f in calls if not f.done()]
        a = min(range(len(self.actors)), key=lambda i: len(self._calls[i]))
        actor = self.actors[a]
        ref = actor.evaluate_chunk.remote(spec_id, chunk.candidates)
        chunk.worker = (a, actor, ref)
        chunk.future = ref.future()
        self._calls[a].append(chunk.future)

    def _lost_worker(self, exc):
        from ray.exceptions import RayActorError, RayTaskError, WorkerCrashedError
        return isinstance(exc, (RayActorError, WorkerCrashedError)) and not isinstance(exc, RayTaskError)

    def _replace_workers(self, lost):
        """An actor Ray could not keep (its restarts used up) is replaced by a new one; one that is only
        unavailable for now (restarting) keeps its place. Ray itself re-sends the calls of an actor it
        restarts (``max_task_retries=-1``): those chunks never fail here."""
        import ray
        unavailable = getattr(ray.exceptions, "ActorUnavailableError", ())
        died = getattr(ray.exceptions, "ActorDiedError", ())
        workers = set()  # actors lost since the last recovery (a chunk may fail after its actor was replaced)
        for c in lost:
            a, actor, _ = c.worker
            if actor is not self.actors[a]:
                continue
            workers.add(a)
            e = c.future.exception()
            if isinstance(e, died) or not isinstance(e, unavailable):
                try:
                    ray.kill(actor, no_restart=True)
                except Exception:  # noqa: BLE001
                    pass
                self.actors[a] = self._new_actor()
                self._calls[a] = []
        return len(workers)

    def _batch_in_flight(self, chunks):
        return 2 * self.workers  # the rest wait here, for the actor that gets free first

    def _cancel(self, chunk):
        """A chunk still queued at its actor is dropped (a running one finishes: actor calls are not
        interrupted)."""
        if chunk.future.done():
            return
        try:  # the future is Ray's: it is answered (TaskCancelledError) rather than cancelled here
            import ray
            ray.cancel(chunk.worker[2])
        except Exception:  # noqa: BLE001 - best effort
            pass

    def actor_pids(self) -> List[int]:
        import ray
        return ray.get([a.pid.remote() for a in self.actors])

    def close(self, now: bool = False):
        import ray
        if not ray.is_initialized():
            return
        for a in getattr(self, "actors", []):
            try:
                ray.kill(a, no_restart=True)
            except Exception:  # noqa: BLE001
                pass
        self.actors = []
        if self._owns:
            ray.shutdown()
            self._owns = False

    def info(self) -> dict:
        d = super().info()
        d["address"] = self.address
        return d
