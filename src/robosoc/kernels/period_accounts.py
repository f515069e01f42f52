"""A sample period's close in one call: the chip's accounting brought up to date, the named
counters of the accounting rows that jobs are charged to, as differences since the last close, and
the routers' counters.

A flight closes a period at every sensor sample (100 Hz); done in Python (numba's accounting call,
numpy's gather of the rows, their difference, and the counters' matrix product at the flight's
end over some 4 kB per period) it cost about a tenth of the default flight's host time.  The
counters are the sparse integer matrix of :func:`robosoc.chip.mpsoc.account_counter_map` applied
to the rows' differences, in integers: exact.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.chip import account_all
from robosoc.kernels.noc import router_counts


@njit(cache=True)
def close_accounts(
    core, book, tiles, tasks, previous, ptr, cols, weights, out, noc_cfg, noc_glob, noc_tile, noc_port, off, routers
) -> None:
    """Attribute everything up to now (:func:`robosoc.kernels.chip.account_all`); then for each
    accounting row r, ``book.acc[tiles[r], tasks[r]]``: its counters' differences since
    ``previous[r]`` into ``out[r]`` (counter c is the sum of ``weights[j] * difference[cols[j]]``
    for j in ``ptr[c]:ptr[c + 1]``), and the row into ``previous[r]``; and the routers' counters
    into ``routers`` (:func:`robosoc.kernels.noc.router_counts`)."""
    account_all(core, book)
    router_counts(noc_cfg, noc_glob, noc_tile, noc_port, off, routers)
    acc = book.acc
    for r in range(tiles.shape[0]):
        row = acc[tiles[r], tasks[r]]
        for c in range(ptr.shape[0] - 1):
            s = 0
            for j in range(ptr[c], ptr[c + 1]):
                k = cols[j]
                s += weights[j] * (row[k] - previous[r, k])
            out[r, c] = s
        for k in range(row.shape[0]):
            previous[r, k] = row[k]


def sparse_rows(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``matrix``'s nonzero entries row by row, as :func:`close_accounts` takes them: (ptr, cols, weights)."""
    rows, cols = np.nonzero(matrix)
    ptr = np.searchsorted(rows, np.arange(matrix.shape[0] + 1)).astype(np.int64)
    return ptr, cols.astype(np.int64), matrix[rows, cols].astype(np.int64)
