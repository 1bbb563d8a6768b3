"""featherdrive_distributed.map_ordered against the list comprehension it stands for, here and on
a 2-worker LocalCluster (one per module: starting it costs seconds)."""
import math
import operator

import numpy as np
import pytest

from featherdrive_distributed import map_ordered


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


ITEMS = [np.arange(k, dtype=float) for k in range(1, 12)]
EXPECTED = [float(np.sum(x * x)) for x in ITEMS]


def test_local_is_the_comprehension():
    assert map_ordered(np.sum, ITEMS) == [np.sum(x) for x in ITEMS]
    assert map_ordered(abs, []) == []


def test_local_failure_names_the_item():
    with pytest.raises(RuntimeError, match=r"item 2 \(-1\.0\) failed: ValueError: math domain"):
        map_ordered(math.sqrt, [4.0, 1.0, -1.0, -2.0])
    with pytest.raises(TypeError, match="fn must be callable"):
        map_ordered(3, [1])


def test_cluster_gives_the_items_results_in_order(client):
    # 40 and 11 tasks over 2 workers finish in any order; the results must come in item order.
    assert map_ordered(operator.neg, list(range(40)), client) == [-k for k in range(40)]
    assert [float(v) for v in map_ordered(np.sum, [x * x for x in ITEMS], client)] == EXPECTED
    assert map_ordered(abs, [], client) == []


def test_cluster_failure_names_the_first_failing_item(client):
    with pytest.raises(RuntimeError, match=r"item 1 \(-9\.0\) failed: ValueError: math domain"):
        map_ordered(math.sqrt, [4.0, -9.0, 1.0, -2.0], client)
    with pytest.raises(TypeError, match="distributed.Client or None"):
        map_ordered(abs, [1], client="tcp://nowhere:1")


def test_sweep_is_the_same_on_1_and_2_threads_and_on_the_cluster(client):
    import featherdrive as fd
    from conftest import ROOT, hexes
    scene = str(ROOT / "examples" / "slider.yaml")
    grid = "stiffness=50:800:3:log,damping=2:60:3"
    one = fd.sweep(scene, grid, num_threads=1)
    two = fd.sweep(scene, grid, num_threads=2)
    # 9 points in chunks of 4: three tasks over two workers, gathered in grid order.
    cluster = fd.sweep(scene, grid, client=client, chunk_size=4)
    assert one.rms.shape == (9, 1) and np.all(np.isfinite(one.rms))
    assert len(set(hexes(one.rms))) == 9  # nine different errors: the order is checked
    for other in (two, cluster):
        assert hexes(other.rms) == hexes(one.rms)
        assert hexes(other.total) == hexes(one.total)
        assert hexes(other.points) == hexes(one.points)
