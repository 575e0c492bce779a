"""Choose one configuration per pose goal so that the whole motion is cheapest.

The goal sequence of a task becomes a chain of *nodes*, each a set of candidate configurations:

- ``Free(key, configs)``: an at/reach goal; any of its IK solutions may be chosen;
- ``Tied()``: a return to the configuration chosen for the first node (``returnTo`` the start when the
  robot starts at its first goal); this closes a cycle, so the first choice is carried through the chain;
- ``Fixed(q)``: a configuration that is given (the start of a follow goal, a fixed start);
- ``Jump(q)``: the motion continues from ``q`` at no cost (the end of a follow goal, whose own motion is fixed).

The cost of moving between consecutive nodes is ``cost(A, B)`` (a matrix over their configurations, e.g.
time-optimal bounds). ``choose`` minimises the sum over the chain by dynamic programming over (first choice,
current choice): O(n0 · Σ n_i · n_{i+1}) with n0 = 1 when no node is tied.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Dict, List, Tuple, Union

import numpy as np


@dataclass
class Free:
    key: str
    configs: np.ndarray  # (n, dof)


@dataclass
class Tied:
    pass


@dataclass
class Fixed:
    q: np.ndarray


@dataclass
class Jump:
    q: np.ndarray


Node = Union[Free, Tied, Fixed, Jump]


def choose(nodes: List[Node], cost: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Tuple[Dict[str, int], float]:
    """The index of the configuration chosen for every ``Free`` node (by key) and the chain's total cost.

    ``Tied`` nodes refer to the first node, which must then be ``Free`` or ``Fixed``."""
    if not nodes:
        return {}, 0.0
    first = nodes[0]
    if isinstance(first, (Tied, Jump)):
        raise ValueError("the chain must start with a Free or Fixed node")
    first_cfg = first.configs if isinstance(first, Free) else np.atleast_2d(first.q)
    tied = any(isinstance(n, Tied) for n in nodes[1:])
    n0 = len(first_cfg) if tied else 1
    m = len(first_cfg)
    if tied:
        best = np.full((n0, m), np.inf)
        best[np.arange(m), np.arange(m)] = 0.0
    else:
        best = np.zeros((1, m))
    cfg = first_cfg
    backs: List[np.ndarray] = []   # per transition: (n0, m_new) index into the previous node's configs
    for node in nodes[1:]:
        if isinstance(node, Jump):
            new_cfg = np.atleast_2d(node.q)
            arg = np.argmin(best, axis=1)[:, None]
            new_best = best[np.arange(n0), arg[:, 0]][:, None]
        else:
            new_cfg = first_cfg if isinstance(node, Tied) else (
                node.configs if isinstance(node, Free) else np.atleast_2d(node.q))
            total = best[:, :, None] + cost(cfg, new_cfg)[None, :, :]     # (n0, m_prev, m_new)
            arg = np.argmin(total, axis=1)
            new_best = np.take_along_axis(total, arg[:, None, :], axis=1)[:, 0, :]
            if isinstance(node, Tied):      # only the first choice itself: keep the diagonal
                diag = np.arange(n0)
                kept = np.full(new_best.shape, np.inf)
                kept[diag, diag] = new_best[diag, diag]
                new_best = kept
        backs.append(arg)
        best, cfg = new_best, new_cfg
    i0, j = np.unravel_index(int(np.argmin(best)), best.shape)
    total_cost = float(best[i0, j])
    idx = [int(j)]
    for arg in reversed(backs):
        idx.append(int(arg[i0, idx[-1]]))
    idx.reverse()
    return {n.key: i for n, i in zip(nodes, idx) if isinstance(n, Free)}, total_cost
