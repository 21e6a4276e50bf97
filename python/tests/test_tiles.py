"""Tile-by-tile modelling from Python: model_tiles / merge_tiles and model_tiled, in one process and
as tasks on a Dask LocalCluster of two worker processes (the same model whatever the split)."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import quadrix


def make_scene(seed):
    """Floor, wall and a pipe of radius 0.5 m along x, all cut by the tile borders x = 0, +-6 m."""
    rng = np.random.default_rng(seed)
    density = 150.0
    parts = []
    n = int(238.0 * density)
    parts.append(np.column_stack([rng.uniform(-11.9, 11.9, n), rng.uniform(1.0, 11.0, n), np.zeros(n)]))
    n = int(95.2 * density)
    parts.append(np.column_stack([rng.uniform(-11.9, 11.9, n), np.full(n, 11.0), rng.uniform(0.0, 4.0, n)]))
    n = int(2.0 * np.pi * 0.5 * 20.0 * density)
    angle = rng.uniform(0.0, 2.0 * np.pi, n)
    parts.append(np.column_stack([rng.uniform(-10.0, 10.0, n), 6.0 + 0.5 * np.cos(angle), 1.5 + 0.5 * np.sin(angle)]))
    points = np.concatenate(parts)
    return (points + rng.normal(0.0, 0.004, points.shape)).astype(np.float32)


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("tiles") / "scene.ply"
    quadrix.write_cloud(path, make_scene(5))
    return path


def test_parts_merged_in_any_order_give_the_model_of_one_process(scene_file):
    parts = [quadrix.model_tiles(str(scene_file), tile=i, tiles=3, tile_size=6.0, margin=1.0) for i in range(3)]
    merged = quadrix.merge_tiles(parts[::-1])
    whole = quadrix.model_tiled(str(scene_file), tile_size=6.0, margin=1.0)
    assert list(merged.types) == list(whole.types)
    np.testing.assert_allclose(merged.records, whole.records, rtol=0, atol=1e-9)
    types = list(whole.types[: whole.quadric_count])
    assert types.count("circular_cylinder") == 1, types
    assert types.count("plane") == 2, types
    with pytest.raises(ValueError, match="missing"):
        quadrix.merge_tiles(parts[:2])


def test_dask_local_cluster_gives_the_same_model(scene_file):
    pytest.importorskip("distributed")
    script = pathlib.Path(__file__).with_name("dask_tiles_script.py")
    run = subprocess.run([sys.executable, str(script), str(scene_file)], capture_output=True, text=True, timeout=300,
                         env=dict(os.environ))
    assert run.returncode == 0, run.stderr[-3000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result["cluster"]["types"] == result["process"]["types"]
    np.testing.assert_allclose(result["cluster"]["records"], result["process"]["records"], rtol=0, atol=1e-9)
    assert result["process"]["types"].count("circular_cylinder") == 1


def test_a_las_tile_in_feet_is_tiled_in_metres_in_one_process(shared_data):
    # Tiles are cut and modelled in metres (tile_size is metres) and the model is returned in the
    # file's feet: the model's primitives lie inside the file's own bounds. Tile groups for separate
    # processes are refused, as their parts are joined in metres whatever file they came from.
    las = shared_data("als_autzen/autzen_trim.las")
    model = quadrix.model_tiled(las, preset="airborne", tile_size=150.0)
    assert model.status == "ok", model.message
    assert model.quadric_count > 10
    cloud = quadrix.read_cloud(las)
    low, high = cloud.points.min(axis=0), cloud.points.max(axis=0)
    inside = np.all((model.center[: model.quadric_count, :2] >= low[:2] - 1.0) &
                    (model.center[: model.quadric_count, :2] <= high[:2] + 1.0), axis=1)
    assert inside.mean() > 0.9, model.center[: model.quadric_count]
    with pytest.raises(ValueError, match="foot"):
        quadrix.model_tiles(las, 0, 2, preset="airborne")
