"""quadrix.map from Python: a small two-session list of the real BALM walk (session a with its
poses as odometry, session b without: registered scan to scan), in one process with the folder and
the evaluation, and on a Dask LocalCluster of two worker processes (the same edges and poses), also
through `quadrix map --scheduler`. Skipped when the walk is absent."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import quadrix

OPTIONS = {"minimum_loop_travel": 3.0, "candidates_per_scan": 1, "place_candidates_per_scan": 1}


@pytest.fixture(scope="module")
def walk(shared_data, tmp_path_factory):
    """Scans 6..13 of the walk (it stands still before), every third point kept: 5 with odometry
    (session a), 3 without (session b). Returns (rows, SCANS.tsv, truth.tsv)."""
    root = shared_data("balm_sequence/poses.txt").parent
    folder = tmp_path_factory.mktemp("walk")
    rows, lines, truth = [], ["session\tscan\todometry"], ["session\tscan\tpose"]
    for index, line in enumerate((root / "poses.txt").read_text().splitlines()[6:14]):
        name, *numbers = line.split()
        points = quadrix.read_cloud(root / name).points[::3]
        path = folder / (name + ".ply")
        quadrix.write_cloud(path, np.ascontiguousarray(points))
        session = "a" if index < 5 else "b"
        pose = np.vstack([np.array(numbers, dtype=float).reshape(3, 4), [0, 0, 0, 1]])
        u, _, vt = np.linalg.svd(pose[:3, :3])
        pose[:3, :3] = u @ vt
        rows.append((session, str(path), pose if session == "a" else None))
        lines.append("%s\t%s\t%s" % (session, path.name, " ".join(repr(v) for v in pose[:3].ravel()) if session == "a" else "-"))
        truth.append("%s\t%s\t%s" % (session, str(path), " ".join(repr(v) for v in pose[:3].ravel())))
    (folder / "scans.tsv").write_text("\n".join(lines) + "\n")
    (folder / "truth.tsv").write_text("\n".join(truth) + "\n")
    return rows, folder / "scans.tsv", folder / "truth.tsv"


def test_map_in_process_writes_the_folder_and_evaluates(walk, tmp_path):
    rows, _, truth = walk
    reports = []
    result = quadrix.map(rows, tmp_path / "map", gt=truth, progress=lambda *report: reports.append(report), **OPTIONS)
    assert ("scans modelled", 8, 8) in reports
    assert ("consecutive scans registered", 2, 2) in reports
    assert result.poses.shape == (8, 4, 4)
    assert result.sessions == ["a"] * 5 + ["b"] * 3
    kinds = [(edge["kind"], edge["status"]) for edge in result.edges]
    assert kinds.count(("odometry", "given")) == 4
    chain = [edge for edge in result.edges if edge["kind"] == "odometry" and edge["status"] != "given"]
    assert [(edge["from"], edge["to"]) for edge in chain] == [(6, 5), (7, 6)]
    assert all(edge["status"] == "ok" for edge in chain), [edge["note"] for edge in chain]
    assert result.candidates_within > 0 and result.candidates_across == 3
    assert all(result.in_map_frame), "session b should join session a"
    evaluation = result.evaluation
    assert evaluation is not None and evaluation["ate_m"] < 0.3, evaluation
    for name in ("poses.tsv", "edges.csv", "report.json", "map.ply", "map_model.qsm", "map.html"):
        assert (tmp_path / "map" / name).exists(), name
    report = json.loads((tmp_path / "map" / "report.json").read_text())
    assert "evaluation" in report
    # The information calibration: one group per session's odometry, as report.json has them.
    written = report["information_groups"]
    assert [group["name"] for group in written] == [group["name"] for group in result.information_groups]
    for stored, returned in zip(written, result.information_groups):
        assert stored["rotation_factor"] == pytest.approx(returned["rotation_factor"], rel=1e-8)
        assert stored["translation_factor"] == pytest.approx(returned["translation_factor"], rel=1e-8)
    assert {"odometry a", "odometry b"} <= {group["name"] for group in result.information_groups}
    assert all(group["rotation_factor"] > 0 and group["translation_factor"] > 0 for group in result.information_groups)
    assert result.out == str(tmp_path / "map")


def test_bad_input_names_the_entry(walk):
    rows, _, _ = walk
    with pytest.raises(ValueError, match=r"scans\[1\]"):
        quadrix.map([rows[0], ("a", "/nonexistent/scan.ply", rows[1][2])] + rows[2:])
    with pytest.raises(TypeError, match="loop_radiuss"):
        quadrix.map(rows, loop_radiuss=3.0)
    with pytest.raises(ValueError, match="candidates_per_scan=-1"):
        quadrix.map(rows, candidates_per_scan=-1)


def test_a_foreign_out_folder_is_refused_before_the_work(walk, tmp_path):
    rows, _, _ = walk
    foreign = tmp_path / "notes"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("not ours")
    with pytest.raises(ValueError, match="notes.txt"):
        quadrix.map(rows, foreign)
    assert [p.name for p in foreign.iterdir()] == ["notes.txt"]


def test_dask_local_cluster_and_the_command_give_the_same_map(walk, tmp_path):
    pytest.importorskip("distributed")
    _, scans, _ = walk
    options = tmp_path / "options.json"
    options.write_text(json.dumps(OPTIONS))
    script = pathlib.Path(__file__).with_name("dask_map_script.py")
    executable = os.environ.get("QUADRIX_EXECUTABLE", "")
    command = [sys.executable, str(script), str(scans), str(options)]
    if executable and pathlib.Path(executable).exists():
        command += [executable, str(tmp_path / "command_map")]
    run = subprocess.run(command, capture_output=True, text=True, timeout=600, env=dict(os.environ))
    assert run.returncode == 0, run.stderr[-3000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    process, cluster = result["process"], result["cluster"]
    print("in process %.1f s, LocalCluster of 2 workers %.1f s" % (process["seconds"], cluster["seconds"]))
    assert len(cluster["edges"]) == len(process["edges"])
    for mine, theirs in zip(process["edges"], cluster["edges"]):
        assert {k: mine[k] for k in ("from", "to", "kind", "status", "used")} == {k: theirs[k] for k in ("from", "to", "kind", "status", "used")}
        np.testing.assert_allclose(theirs["transform"], mine["transform"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(cluster["poses"], process["poses"], rtol=0, atol=1e-9)
    assert result["worker_error"] is not None and "row 3 (small.ply)" in result["worker_error"], result["worker_error"]
    assert "at least 100" in result["worker_error"]
    if result["command"] is not None:
        assert result["command"]["code"] == 0, result["command"]["stderr"]
        table = [line.split("\t") for line in (tmp_path / "command_map" / "poses.tsv").read_text().splitlines()[1:]]
        written = np.array([[float(v) for v in row[2:14]] for row in table]).reshape(-1, 3, 4)
        np.testing.assert_allclose(written, np.array(process["poses"])[:, :3, :], rtol=0, atol=1e-6)


def test_scheduler_errors_are_clear(walk, tmp_path):
    executable = os.environ.get("QUADRIX_EXECUTABLE", "")
    if not executable or not pathlib.Path(executable).exists():
        pytest.skip("quadrix executable not known (QUADRIX_EXECUTABLE)")
    _, scans, _ = walk
    missing = subprocess.run([executable, "map", str(scans), "--out", str(tmp_path / "m"), "--scheduler", "tcp://127.0.0.1:9"],
                             capture_output=True, text=True, env=dict(os.environ, QUADRIX_PYTHON="/nonexistent/python3"))
    assert missing.returncode == 2 and "/nonexistent/python3 cannot be started" in missing.stderr, missing.stderr
    assert not (tmp_path / "m").exists()
