"""One BLAS thread for every teachbot run.

The matrices are small, so extra BLAS threads only spin; and a multi-threaded
reduction sums in another order, which can tip a near tie between two
questions, so the same seed would give another transcript on another core
count. ``teachbot`` commands and regression workers run inside this limit.
"""

from __future__ import annotations


def one_blas_thread():
    """A context manager limiting BLAS to one thread (threadpoolctl)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")
