"""quadrix.Cloud, read_cloud and write_cloud: round trips, array layouts and errors."""
import numpy as np
import pytest

import quadrix


def random_points(count, seed=1):
    return np.random.default_rng(seed).uniform(-50.0, 50.0, size=(count, 3)).astype(np.float32)


@pytest.mark.parametrize("extension", ["ply", "pcd"])
@pytest.mark.parametrize("binary", [True, False])
def test_write_then_read_returns_the_same_points_and_fields(tmp_path, extension, binary):
    points = random_points(1000)
    intensity = np.linspace(0.0, 1.0, len(points), dtype=np.float32)
    labels = np.arange(len(points), dtype=np.uint32) % 7
    path = tmp_path / f"cloud.{extension}"
    quadrix.write_cloud(path, points, intensity=intensity, labels=labels, binary=binary)
    cloud = quadrix.read_cloud(path)
    assert len(cloud) == len(points)
    assert cloud.points.dtype == np.float32 and cloud.points.shape == (1000, 3)
    if binary:
        np.testing.assert_array_equal(cloud.points, points)
        np.testing.assert_array_equal(cloud.intensity, intensity)
    else:  # ASCII keeps float's round-trip digits
        np.testing.assert_allclose(cloud.points, points, rtol=1e-6)
        np.testing.assert_allclose(cloud.intensity, intensity, rtol=1e-6)
    np.testing.assert_array_equal(cloud.labels, labels)
    assert cloud.source == str(path)


def test_a_cloud_is_written_with_every_field_it_carries(tmp_path):
    points = random_points(50)
    original = quadrix.Cloud(points, intensity=np.ones(50), labels=np.full(50, 3))
    quadrix.write_cloud(tmp_path / "a.ply", original)
    again = quadrix.read_cloud(tmp_path / "a.ply")
    np.testing.assert_array_equal(again.points, points)
    np.testing.assert_array_equal(again.intensity, np.ones(50, dtype=np.float32))
    np.testing.assert_array_equal(again.labels, np.full(50, 3, dtype=np.uint32))


def test_kitti_bin_has_points_and_intensity(shared_data):
    path = shared_data("kitti00/velodyne/000000.bin")
    cloud = quadrix.read_cloud(str(path))
    raw = np.fromfile(path, dtype=np.float32).reshape(-1, 4)
    assert len(cloud) == len(raw)  # the frame has no non-finite points
    np.testing.assert_array_equal(cloud.points, raw[:, :3])
    np.testing.assert_array_equal(cloud.intensity, raw[:, 3])
    assert cloud.labels is None


def test_any_real_layout_gives_the_same_positions():
    points = random_points(200)
    reference = quadrix.Cloud(points).points
    layouts = [
        points.astype(np.float64),
        np.asfortranarray(points),
        np.ascontiguousarray(np.hstack([points, points])[:, :3]),
        np.hstack([points, points])[:, 3:],  # a strided view
        points.tolist(),
    ]
    for layout in layouts:
        np.testing.assert_array_equal(quadrix.Cloud(layout).points, reference)
    integers = np.arange(30, dtype=np.int64).reshape(10, 3)
    np.testing.assert_array_equal(quadrix.Cloud(integers).points, integers.astype(np.float32))


def test_points_are_a_read_only_view_that_keeps_the_cloud_alive():
    points = quadrix.Cloud(random_points(10)).points  # the Cloud itself is dropped at once
    assert not points.flags.writeable
    np.testing.assert_array_equal(points, random_points(10))


def test_missing_file_is_file_not_found_naming_it(tmp_path):
    missing = tmp_path / "missing.ply"
    with pytest.raises(FileNotFoundError, match="missing.ply"):
        quadrix.read_cloud(missing)
    with pytest.raises(FileNotFoundError, match="missing.ply"):
        quadrix.register(missing, random_points(10))
    with pytest.raises(FileNotFoundError, match="no_such_folder"):
        quadrix.write_cloud(tmp_path / "no_such_folder" / "a.ply", random_points(10))


def test_unparsable_file_is_value_error_naming_it(tmp_path):
    broken = tmp_path / "broken.ply"
    broken.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(ValueError, match="broken.ply"):
        quadrix.read_cloud(broken)
    with pytest.raises(ValueError, match="cloud.xyz"):
        quadrix.write_cloud(tmp_path / "cloud.xyz", random_points(10))


def test_bad_arrays_are_value_errors():
    with pytest.raises(ValueError, match=r"\(N, 3\).*\(10, 4\)"):
        quadrix.Cloud(np.zeros((10, 4)))
    bad = random_points(10)
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match=r"points\[7\]"):
        quadrix.Cloud(bad)
    with pytest.raises(ValueError, match="labels"):
        quadrix.Cloud(random_points(10), labels=np.zeros(9, dtype=np.uint32))
