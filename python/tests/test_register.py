"""quadrix.register: the same answer and report as `quadrix register`, on simulated and real pairs."""
import json

import numpy as np
import pytest

import quadrix


def rotation_error_degrees(estimate, truth):
    cosine = (np.trace(estimate[:3, :3].T @ truth[:3, :3]) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


@pytest.fixture(scope="module")
def street_result(street):
    pair = street["pairs"][0]
    return quadrix.register(street["clouds"][pair["source"]], street["clouds"][pair["target"]],
                            ground_truth=pair["transform"]), pair


def test_the_simulated_street_pair_registers(street_result):
    result, pair = street_result
    assert result.status == "ok" and result.ok, result.message
    assert result.transform.shape == (4, 4)
    assert np.linalg.norm(result.transform[:3, 3] - pair["transform"][:3, 3]) < 0.2
    assert rotation_error_degrees(result.transform, pair["transform"]) < 1.0
    assert result.ground_truth["success"] is True


def test_the_result_is_report_json(street_result):
    result, _ = street_result
    report = json.loads(result.to_json())
    assert report == result.report
    np.testing.assert_array_equal(np.array(report["transform"]), result.transform)
    assert report["status"] == result.status and report["message"] == result.message
    assert result.timings_ms == report["timings_ms"] and result.timings_ms["total"] >= result.timings_ms["registration"]
    assert result.counts == report["counts"] and result.counts["correspondences"] > 0
    assert result.candidates == report["candidates"] and sum(c["selected"] for c in result.candidates) == 1
    assert result.overlap == report["overlap"] and result.overlap["transformed"] > result.overlap["identity"]
    # The right `ok` answer leaves the other sensor's free space nearly empty, each way.
    assert result.free_space == report["free_space"] and result.free_space["demoted"] is False
    assert result.free_space["sum"] < 0.2 and min(result.free_space["source_tested"], result.free_space["target_tested"]) >= 100
    assert result.source_model.quadric_count == result.counts["source_quadrics"]


def test_arrays_clouds_and_float64_give_the_same_answer(street, street_result):
    result, pair = street_result
    source, target = street["clouds"][pair["source"]], street["clouds"][pair["target"]]
    from_arrays = quadrix.register(np.array(source.points), target.points.astype(np.float64))
    np.testing.assert_array_equal(from_arrays.transform, result.transform)
    assert from_arrays.counts == result.counts


def test_registering_a_pair_from_files_matches_the_command_line(tmp_path, quadrix_cli, street):
    pair = street["pairs"][0]
    source, target = tmp_path / "source.ply", tmp_path / "target.ply"
    quadrix.write_cloud(source, street["clouds"][pair["source"]])
    quadrix.write_cloud(target, street["clouds"][pair["target"]])
    quadrix_cli("register", source, target, "--out", tmp_path / "out")
    printed = json.loads((tmp_path / "out" / "report.json").read_text())
    result = quadrix.register(source, target)
    assert_same_report(result, printed)


def assert_same_report(result, printed):
    """The Python result and the CLI's report.json agree on everything but wall times."""
    np.testing.assert_array_equal(result.transform, np.array(printed["transform"]))
    assert result.status == printed["status"] and result.message == printed["message"]
    assert result.counts == printed["counts"]
    assert result.report.keys() == printed.keys()
    assert result.timings_ms.keys() == printed["timings_ms"].keys()
    assert result.report["input"] == printed["input"]
    assert result.candidates == printed["candidates"]
    assert result.overlap == printed["overlap"]


def test_kitti_loop_closure_matches_the_command_line(tmp_path, shared_data, quadrix_cli):
    source = shared_data("kitti00/velodyne/000000.bin")
    target = shared_data("kitti00/velodyne/004438.ply")
    truth_file = shared_data("kitti00/gt/T_004438_from_000000.txt")
    truth = np.loadtxt(truth_file).reshape(4, 4)
    quadrix_cli("register", source, target, "--gt", truth_file, "--out", tmp_path / "out")
    printed = json.loads((tmp_path / "out" / "report.json").read_text())
    result = quadrix.register(str(source), str(target), ground_truth=truth)
    assert result.status == "ok", result.message
    assert result.ground_truth["success"] is True
    assert_same_report(result, printed)
    assert result.ground_truth == printed["ground_truth"]


def test_the_kitti_pair_thirty_metres_apart_is_found_by_the_ground_correlation(shared_data):
    source = shared_data("kitti00/velodyne/000052.bin")
    target = shared_data("kitti00/velodyne/000088.bin")
    truth = np.loadtxt(shared_data("kitti00/gt/T_000088_from_000052.txt")).reshape(4, 4)
    result = quadrix.register(str(source), str(target), ground_truth=truth)
    assert result.status == "ok", result.message
    assert result.ground_truth["success"] is True
    poses = result.ground_correlation
    assert poses is not None and 1 <= len(poses) <= 6
    shares = [pose["share"] for pose in poses]
    assert shares == sorted(shares, reverse=True) and 0.0 < shares[0] <= 1.0
    # One of the poses the dense search started from lies near the truth, and the search's best came from it.
    nearest = min(np.linalg.norm(np.array(pose["transform"])[:3, 3] - truth[:3, 3]) for pose in poses)
    assert nearest < 1.5
    best = result.dense_search["optima"][result.dense_search["best"]]
    assert best["start"].startswith("correlation"), best["start"]


def map_pose(yaw_degrees, translation):
    """A 4x4 pose: a turn about the up axis, then a translation."""
    c, s = np.cos(np.radians(yaw_degrees)), np.sin(np.radians(yaw_degrees))
    pose = np.eye(4)
    pose[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    pose[:3, 3] = translation
    return pose


def test_clouds_in_a_map_frame_register_with_their_sensor_origins(tmp_path, shared_data, quadrix_cli):
    # A loop closure as a mapping system holds it: each scan in the map's frame, its sensor hundreds
    # of metres from the map's origin, the two scans' poses in the map drifted apart.
    truth_between_sensors = np.loadtxt(shared_data("kitti00/gt/T_004438_from_000000.txt")).reshape(4, 4)
    source_pose, target_pose = map_pose(-70.0, [812.5, -340.0, 21.0]), map_pose(35.0, [806.0, -331.0, 20.5])
    source_points = np.array(quadrix.read_cloud(str(shared_data("kitti00/velodyne/000000.bin"))).points, np.float64)
    target_points = np.array(quadrix.read_cloud(str(shared_data("kitti00/velodyne/004438.ply"))).points, np.float64)
    source = source_points @ source_pose[:3, :3].T + source_pose[:3, 3]
    target = target_points @ target_pose[:3, :3].T + target_pose[:3, 3]
    truth = target_pose @ truth_between_sensors @ np.linalg.inv(source_pose)
    origins = dict(source_origin=source_pose[:3, 3], target_origin=target_pose[:3, 3])

    result = quadrix.register(source, target, ground_truth=truth, **origins)
    assert result.status == "ok", result.message
    assert result.ground_truth["success"] is True and result.ground_truth["rte_m"] < 0.3
    # The transform is between the frames given: the source sensor lands where the truth puts it.
    sensor = np.append(source_pose[:3, 3], 1.0)
    assert np.linalg.norm((result.transform @ sensor)[:3] - (truth @ sensor)[:3]) < 0.3
    assert np.allclose(result.report["sensor_origins"]["transform_between_files"], result.transform)

    # Without them every point lies beyond the sensor's range from the map's origin: a status that
    # names the frame, not an answer.
    unplaced = quadrix.register(source, target)
    assert unplaced.status == "degenerate" and "sensor's frame" in unplaced.message

    source_file, target_file, truth_file = tmp_path / "source.ply", tmp_path / "target.ply", tmp_path / "truth.txt"
    quadrix.write_cloud(str(source_file), quadrix.Cloud(source.astype(np.float32)))
    quadrix.write_cloud(str(target_file), quadrix.Cloud(target.astype(np.float32)))
    np.savetxt(truth_file, truth)
    printed = quadrix_cli("register", source_file, target_file, "--gt", truth_file, "--out", tmp_path / "out",
                          "--source-origin", ",".join(map(str, origins["source_origin"])),
                          "--target-origin", ",".join(map(str, origins["target_origin"])), "--no-page")
    assert "SUCCESS" in printed
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["status"] == "ok" and report["ground_truth"]["success"] is True
    between_files = np.array(report["sensor_origins"]["transform_between_files"])
    assert np.linalg.norm((between_files @ sensor)[:3] - (truth @ sensor)[:3]) < 0.3
    printed_matrix = np.array([[float(v) for v in line.split()] for line in printed.splitlines()[2:6]])
    np.testing.assert_allclose(printed_matrix, between_files, atol=1e-5)
    # merged.ply is in the target file's frame: the target's points come back unmoved.
    merged = np.array(quadrix.read_cloud(str(tmp_path / "out" / "merged.ply")).points)
    np.testing.assert_allclose(merged[: len(target)], target.astype(np.float32), atol=1e-3)


def test_refiner_and_presets_are_checked():
    points = np.random.default_rng(1).uniform(-10, 10, (100, 3))
    with pytest.raises(ValueError, match="gauss"):
        quadrix.register(points, points, preset="vlp64", refiner="gauss")
    with pytest.raises(ValueError, match="vlp32"):
        quadrix.register(points, points, preset="vlp32")


def test_too_little_structure_is_a_status_not_an_exception():
    points = np.random.default_rng(1).uniform(-10, 10, (10, 3))
    result = quadrix.register(points, points, preset="vlp64")
    assert result.status == "degenerate" and not result.ok
    assert "correspondences" in result.message
    np.testing.assert_array_equal(result.transform, np.eye(4))


def test_the_docstring_explains_the_arguments():
    text = quadrix.register.__doc__
    for word in ("source", "target", "preset", "config", "refiner", "ground_truth", "transform", "status", "GIL"):
        assert word in text


def test_a_scan_in_feet_is_refused_not_registered_as_metres(shared_data):
    las = shared_data("als_autzen/autzen_trim.las")
    with pytest.raises(ValueError, match="foot.*metres"):
        quadrix.register(las, las)
