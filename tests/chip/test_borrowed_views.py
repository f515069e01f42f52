"""The kernels' borrowed arrays (robosoc.kernels.borrowed): the same memory as the array, no reference."""

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from robosoc.kernels.borrowed import borrow, row


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
