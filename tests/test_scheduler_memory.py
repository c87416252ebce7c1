"""A local process pool hands each result over and keeps no reference to it, so streaming
many runs (``iter_jobs``) holds only the results the caller keeps."""

import gc
import weakref

import numpy as np

from shoal.studies.experiments.schedulers import LocalPool


def _result(i: int) -> np.ndarray:
    return np.full(1000, float(i))


def test_local_pool_keeps_no_yielded_result():
    refs = []
    for n, (i, res) in enumerate(LocalPool(2).map_unordered(_result, list(range(8)))):
        assert res[0] == i
        refs.append(weakref.ref(res))
        del res
        if n >= 4:  # while the pool is still running: only the newest may still be referenced
            gc.collect()
            assert [r() is None for r in refs[:-1]] == [True] * (len(refs) - 1)
    assert len(refs) == 8
