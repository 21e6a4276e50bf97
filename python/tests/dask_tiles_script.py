"""Models a small static scene tile by tile on a Dask LocalCluster of two worker processes and in
one process, and prints both models as JSON (run by test_tiles.py as a script: a LocalCluster with
processes=True starts its workers by re-importing __main__, so it must start under the guard below).

    python3 dask_tiles_script.py SCENE.ply
"""
import json
import sys

import numpy as np

import quadrix


def summary(model):
    """Types and records of a model, for comparison across processes."""
    return {"types": list(model.types[: model.quadric_count]), "records": model.records[: model.quadric_count].tolist()}


if __name__ == "__main__":
    from distributed import Client, LocalCluster

    path = sys.argv[1]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        on_cluster = quadrix.model_tiled(path, tile_size=6.0, margin=1.0, client=client, tiles=3)
    in_process = quadrix.model_tiled(path, tile_size=6.0, margin=1.0)
    print(json.dumps({"cluster": summary(on_cluster), "process": summary(in_process)}))
