"""How a sweep cuts its variants into batches by default (issue 27, item 3): every worker gets about
as many variants, so no worker's extra batch sets the sweep's end."""
from __future__ import annotations

import pytest

from mtbmj.sweep.runner import _even_batches


@pytest.mark.parametrize("n, workers", [(200, 2), (1000, 2), (37, 2), (5, 2), (1, 4), (16, 2), (20000, 2), (101, 3)])
def test_each_variant_once_in_order_and_shares_even(n, workers):
    variants = list(range(n))
    batches = _even_batches(variants, workers)
    assert [v for b in batches for v in b] == variants  # each once, in the plan's order
    sizes = [len(b) for b in batches]
    assert min(sizes) >= 1 and max(sizes) - min(sizes) <= 1
    assert max(sizes) <= 16
    if n >= workers:
        # dealt round robin, as a pool of equal workers takes them: shares within one batch's size
        shares = [sum(sizes[k::workers]) for k in range(workers)]
        assert max(shares) - min(shares) <= 1


def test_two_hundred_on_two_workers():
    # the benchmark's sweep: 18 batches of 11 or 12, 100 variants a worker (12 a batch gave 17 batches,
    # 108 variants on one worker)
    sizes = [len(b) for b in _even_batches(list(range(200)), 2)]
    assert len(sizes) == 18 and set(sizes) == {11, 12}
    assert sum(sizes[0::2]) == sum(sizes[1::2]) == 100


def test_empty():
    assert _even_batches([], 2) == []
