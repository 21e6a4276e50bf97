"""quadrix.model, Model.save / load_model round trips, and quadrix.fit against `quadrix fit`."""
import json

import numpy as np
import pytest

import quadrix


@pytest.fixture(scope="module")
def street_model(street):
    return quadrix.model(street["clouds"][0], preset="vlp64")


def test_the_street_model_has_ground_walls_and_poles(street_model):
    model = street_model
    assert model.status == "ok"
    assert model.quadric_count > 5
    assert len(model) == model.quadric_count + len(model.augmented_points)
    assert {"ground", "plane"} <= set(model.classes[: model.quadric_count])
    assert model.records.shape == (len(model), 21)
    np.testing.assert_array_equal(model.records[:, 0], model.labels)
    np.testing.assert_array_equal(model.records[:, 1:11], model.q)
    np.testing.assert_array_equal(model.records[:, 18:21], model.center)
    np.testing.assert_allclose(np.linalg.norm(model.rotation, axis=1), 1.0, atol=1e-9)
    assert model.ground["found"] and model.ground["normal"][2] > 0.9
    assert model.source_points == len(quadrix.synth("street", seed=3, primitives=False)["clouds"][0])


@pytest.mark.parametrize("name", ["model.json", "model.qsm"])
def test_save_then_load_returns_the_same_model(tmp_path, street_model, name):
    path = tmp_path / name
    street_model.save(path)
    loaded = quadrix.load_model(path)
    np.testing.assert_array_equal(loaded.records, street_model.records)
    assert loaded.types == street_model.types
    np.testing.assert_array_equal(loaded.point_counts, street_model.point_counts)
    np.testing.assert_array_equal(loaded.augmented_descriptors, street_model.augmented_descriptors)
    assert loaded.ground == street_model.ground
    assert loaded.status == street_model.status
    assert loaded.to_json() == street_model.to_json()


def test_to_json_is_the_cli_model_format(street_model):
    document = json.loads(street_model.to_json())
    assert document["format"] == "quadrix-scene-model"
    assert len(document["quadrics"]) == len(street_model)


def test_damaged_model_files_are_value_errors_naming_them(tmp_path, street_model):
    path = tmp_path / "model.qsm"
    street_model.save(path)
    data = bytearray(path.read_bytes())
    data[40] ^= 0xFF
    damaged = tmp_path / "damaged.qsm"
    damaged.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="damaged.qsm"):
        quadrix.load_model(damaged)
    with pytest.raises(FileNotFoundError, match="absent.qsm"):
        quadrix.load_model(tmp_path / "absent.qsm")


def cylinder_points(count=3000, seed=4):
    """Points on a vertical cylinder of radius 0.4 m around (2, -1), 3 m tall, with 5 mm noise."""
    rng = np.random.default_rng(seed)
    angle = rng.uniform(0.0, 2.0 * np.pi, count)
    height = rng.uniform(0.0, 3.0, count)
    radius = 0.4 + rng.normal(0.0, 0.005, count)
    return np.column_stack([2.0 + radius * np.cos(angle), -1.0 + radius * np.sin(angle), height]).astype(np.float32)


def test_fit_finds_the_cylinder():
    fit = quadrix.fit(cylinder_points(), type="cylinder", fitter="constrained")
    assert fit["status"] == "ok" and fit["type"] == "circular_cylinder"
    assert sorted(fit["scale"])[1:] == pytest.approx([0.4, 0.4], abs=0.01)
    assert fit["residual_rms"] < 0.01


@pytest.mark.parametrize("fitter", ["statistical", "taubin", "constrained"])
def test_fit_returns_what_the_cli_prints(tmp_path, quadrix_cli, fitter):
    path = tmp_path / "segment.ply"
    quadrix.write_cloud(path, cylinder_points())
    printed = json.loads(quadrix_cli("fit", path, "--type", "cylinder", "--fitter", fitter))
    fitted = quadrix.fit(path, type="cylinder", fitter=fitter)
    assert fitted.keys() == printed.keys()  # the CLI prints them sorted (nlohmann::json)
    timings = {"time_ms", "evaluation_ms"}
    assert {k: v for k, v in fitted.items() if k not in timings} == {k: v for k, v in printed.items() if k not in timings}


def test_fit_rejects_unknown_names():
    with pytest.raises(ValueError, match="hyperboloid"):
        quadrix.fit(cylinder_points(), type="hyperboloid")
    with pytest.raises(ValueError, match="newton"):
        quadrix.fit(cylinder_points(), fitter="newton")


def test_a_cloud_in_a_map_frame_is_modelled_around_its_sensor_origin(street):
    # Coordinates on a 1/1024 m grid, so moving them 770 m out and back is exact in float32 and both
    # models see the very same points.
    points = np.round(np.asarray(street["clouds"][0].points, np.float64) * 1024.0) / 1024.0
    origin = np.array([640.0, -384.0, 24.0])
    in_sensor_frame = quadrix.model(points.astype(np.float32), preset="vlp64")
    in_map_frame = quadrix.model((points + origin).astype(np.float32), preset="vlp64", sensor_origin=origin)
    assert in_map_frame.status == "ok", in_map_frame.message
    assert in_map_frame.types == in_sensor_frame.types
    np.testing.assert_allclose(in_map_frame.center, in_sensor_frame.center + origin, atol=1e-6)
    normal = np.array(in_sensor_frame.ground["normal"])
    assert in_map_frame.ground["offset"] == pytest.approx(in_sensor_frame.ground["offset"] - normal @ origin, abs=1e-6)
    with pytest.raises(ValueError, match="sensor_origin"):
        quadrix.model(points.astype(np.float32), preset="vlp64", sensor_origin=[1.0, 2.0])


def test_a_las_tile_in_feet_is_modelled_as_the_cli_models_it(tmp_path, shared_data, quadrix_cli):
    # The real airborne tile declares state-plane feet: model() reads it relative to a local origin,
    # models it in metres and returns the model in the file's feet, as `quadrix model` does; a Cloud
    # read with local_origin="auto" carries its units and origin and gives the same model.
    las = shared_data("als_autzen/autzen_trim.las")
    from_path = quadrix.model(las, preset="airborne")
    assert from_path.status == "ok", from_path.message
    quadrix_cli("model", las, "--preset", "airborne", "--no-page", "--out", tmp_path / "cli.json")
    cli = json.loads((tmp_path / "cli.json").read_text())
    assert cli["stats"]["units"]["name"] == "foot"
    assert from_path.types == [q["type"] for q in cli["quadrics"]]
    np.testing.assert_allclose(from_path.center, [q["center"] for q in cli["quadrics"]], rtol=0, atol=1e-6)
    cloud = quadrix.read_cloud(las, local_origin="auto")
    assert cloud.units["name"] == "foot" and cloud.units["metres_per_unit"] == pytest.approx(0.3048)
    assert min(abs(cloud.local_origin[0]), abs(cloud.local_origin[1])) > 1e5  # state-plane feet
    from_cloud = quadrix.model(cloud, preset="airborne")
    np.testing.assert_array_equal(from_cloud.records, from_path.records)
    with pytest.raises(ValueError, match="local_origin"):
        quadrix.read_cloud(las, local_origin="centre")
