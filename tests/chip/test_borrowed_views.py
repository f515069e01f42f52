"""The kernels' borrowed arrays (robosoc.kernels.borrowed): the same memory as the array, no reference."""

import sys
from typing import NamedTuple

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError
from numba.typed import List

from robosoc.kernels.borrowed import borrow, item, row


class _Pair(NamedTuple):
    a: np.ndarray
    b: np.ndarray


@njit
def _bump_row(a, t):  # type: ignore[no-untyped-def]
    r = row(a, t)
    for i in range(r.shape[0]):
        r[i] += i + 1
    return r.shape[0], r.sum()


@njit
def _bump_borrowed(a):  # type: ignore[no-untyped-def]
    b = borrow(a)
    b[1, 2] = 99
    return b.shape, b.strides


def test_row_is_the_row_in_place() -> None:
    a = np.arange(12, dtype=np.int64).reshape(3, 4)
    expected = a.copy()
    expected[1] += np.arange(1, 5)
    n, total = _bump_row(a, 1)
    assert n == 4 and total == expected[1].sum()
    assert np.array_equal(a, expected)


def test_row_of_a_narrow_dtype_steps_by_its_item_size() -> None:
    a = np.zeros((4, 6), dtype=np.uint8)
    _bump_row(a, 3)
    assert a[3].tolist() == [1, 2, 3, 4, 5, 6] and not a[:3].any()


def test_borrow_is_the_same_array() -> None:
    a = np.zeros((3, 5), dtype=np.int32)
    shape, strides = _bump_borrowed(a)
    assert shape == a.shape and strides == a.strides and a[1, 2] == 99 and a.sum() == 99


def test_row_refuses_what_is_not_a_contiguous_2d_array() -> None:
    with pytest.raises(TypingError):
        _bump_row(np.zeros(4, dtype=np.int64), 0)
    with pytest.raises(TypingError):
        _bump_row(np.zeros((4, 4), dtype=np.int64)[:, ::2], 0)


@njit
def _bump_item(items, t):  # type: ignore[no-untyped-def]
    p = item(items, t)
    p.a[0] += 5
    p.b[-1] = -1.5
    return p.a.shape[0], p.b.shape[0], p.a.sum()


@njit
def _sum_items(items):  # type: ignore[no-untyped-def]
    total = 0
    for t in range(len(items)):
        total += item(items, t).a.sum()
    return total


def test_item_is_the_lists_tuple_in_place() -> None:
    pairs = [_Pair(np.arange(k + 2, dtype=np.int64), np.zeros(3, dtype=np.float64)) for k in range(3)]
    items = List(pairs)
    n, m, total = _bump_item(items, 1)
    assert (n, m, total) == (3, 3, 0 + 1 + 2 + 5)
    assert pairs[1].a.tolist() == [5, 1, 2] and pairs[1].b.tolist() == [0.0, 0.0, -1.5]
    assert pairs[0].a.tolist() == [0, 1] and pairs[2].a.tolist() == [0, 1, 2, 3] and not pairs[2].b.any()
    assert _sum_items(items) == 1 + (8) + 6


def test_item_counts_no_reference() -> None:
    # the list's getitem counts one reference per array and gives it back; the borrowed item never
    # touches the count, so a dangling decrement would show as a count below the start
    pair = _Pair(np.arange(4, dtype=np.int64), np.ones(2, dtype=np.float64))
    items = List([pair])
    before = (sys.getrefcount(pair.a), sys.getrefcount(pair.b))
    for _ in range(50):
        _bump_item(items, 0)
        _sum_items(items)
    assert (sys.getrefcount(pair.a), sys.getrefcount(pair.b)) == before
    assert pair.a[0] == 250 and pair.b[-1] == -1.5


def test_item_refuses_a_list_of_what_is_not_a_tuple_of_arrays() -> None:
    with pytest.raises(TypingError):
        _bump_item(List([np.zeros(3)]), 0)
