"""Maps a small scan list in one process and on a Dask LocalCluster of two worker processes, and
prints both results as JSON (run by test_map.py as a script: a LocalCluster with processes=True
starts its workers by re-importing __main__, so it must start under the guard below). With a
quadrix executable as third argument, also runs `quadrix map --scheduler` against the same cluster.

    python3 dask_map_script.py SCANS.tsv OPTIONS.json [QUADRIX_EXECUTABLE OUT_FOLDER]
"""
import json
import pathlib
import subprocess
import sys
import time


def summary(result, seconds):
    """Edges (without timings), poses and the run's time, for comparison across processes."""
    edges = [{"from": e["from"], "to": e["to"], "kind": e["kind"], "status": e["status"], "used": e["used"],
              "transform": e["transform"].tolist()} for e in result.edges]
    return {"edges": edges, "poses": result.poses.tolist(), "seconds": seconds}


if __name__ == "__main__":
    import numpy as np
    from distributed import Client, LocalCluster

    import quadrix

    scans, options = sys.argv[1], json.load(open(sys.argv[2]))
    start = time.perf_counter()
    in_process = summary(quadrix.map(scans, **options), time.perf_counter() - start)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        client.wait_for_workers(2)
        start = time.perf_counter()
        on_cluster = summary(quadrix.map(scans, client=client, **options), time.perf_counter() - start)
        # A worker's error comes back as the same ValueError naming the row.
        bad = pathlib.Path(scans).with_name("bad_scans.tsv")
        small = pathlib.Path(scans).with_name("small.ply")
        quadrix.write_cloud(small, np.zeros((50, 3), dtype=np.float32) + np.arange(50, dtype=np.float32)[:, None])
        first = pathlib.Path(scans).read_text().splitlines()[1].split("\t")
        bad.write_text("session\tscan\todometry\na\t%s\t-\na\tsmall.ply\t-\n" % first[1])
        try:
            quadrix.map(str(bad), client=client)
            worker_error = None
        except ValueError as error:
            worker_error = str(error)
        command = None
        if len(sys.argv) > 4:
            arguments = [sys.argv[3], "map", scans, "--out", sys.argv[4], "--scheduler", cluster.scheduler_address]
            for key, flag in (("minimum_loop_travel", "--minimum-loop-travel"), ("candidates_per_scan", "--candidates-per-scan"),
                              ("place_candidates_per_scan", "--place-candidates")):
                if key in options:
                    arguments += [flag, str(options[key])]
            run = subprocess.run(arguments, capture_output=True, text=True)
            command = {"code": run.returncode, "stdout": run.stdout, "stderr": run.stderr[-3000:]}
    print(json.dumps({"process": in_process, "cluster": on_cluster, "command": command, "worker_error": worker_error}))
