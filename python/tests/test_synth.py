"""quadrix.synth: the clouds and ground truth of `quadrix synth`."""
import numpy as np
import pytest

import quadrix


def test_synth_is_deterministic_and_has_ground_truth(street):
    again = quadrix.synth("street", seed=3, sensor="hdl64", primitives=False)
    assert len(street["clouds"]) == len(again["clouds"]) == 2
    for first, second in zip(street["clouds"], again["clouds"]):
        np.testing.assert_array_equal(first.points, second.points)
        assert first.labels is not None and "primitive_id" in first.fields
    pair = street["pairs"][0]
    assert (pair["source"], pair["target"]) == (1, 0)
    poses = street["poses"]
    np.testing.assert_allclose(pair["transform"], np.linalg.inv(poses[0]) @ poses[1], atol=1e-12)


def test_synth_writes_the_cli_folder(tmp_path, quadrix_cli):
    data = quadrix.synth("corridor", seed=2, sensor="vlp16", out=tmp_path / "py")
    quadrix_cli("synth", "corridor", "--seed", 2, "--sensor", "vlp16", "--out", tmp_path / "cli")
    assert data["files"] and "pairs.tsv" in data["files"]
    for name in data["files"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    cloud = quadrix.read_cloud(tmp_path / "cli" / "scan_000.ply")
    np.testing.assert_array_equal(cloud.points, data["clouds"][0].points)
    truth = np.loadtxt(tmp_path / "cli" / "T_000_from_001.txt").reshape(4, 4)
    np.testing.assert_allclose(data["pairs"][0]["transform"], truth, atol=1e-9)
    assert len(data["primitives"]) > 0


def test_explicit_poses_and_overrides():
    poses = [np.eye(4), np.eye(4)]
    poses[1][:3, 3] = [2.0, 0.0, 0.0]
    data = quadrix.synth("street", seed=1, sensor="vlp16", poses=poses, noise=0.0, dropout=0.0, primitives=False)
    np.testing.assert_allclose(data["pairs"][0]["transform"][:3, 3], [2.0, 0.0, 0.0], atol=1e-12)
    spec = quadrix.synth("street", seed=1, sensor="vlp16", poses="0,0,0,0;2,0,0,0", noise=0.0, dropout=0.0,
                         primitives=False)
    np.testing.assert_array_equal(spec["clouds"][1].points, data["clouds"][1].points)


def test_names_are_listed_and_checked():
    assert set(quadrix.scenes()) == {"street", "corridor", "monument"}
    assert {"hdl64", "vlp16", "livox", "tls"} <= set(quadrix.sensors())
    with pytest.raises(ValueError, match="highway"):
        quadrix.synth("highway")
    with pytest.raises(ValueError, match="hdl32"):
        quadrix.synth("street", sensor="hdl32")


def test_porous_foliage_matches_the_cli_and_adds_vegetation(tmp_path, quadrix_cli):
    leafy = quadrix.synth("street", seed=11, sensor="hdl64", foliage="porous", out=tmp_path / "py")
    quadrix_cli("synth", "street", "--seed", 11, "--sensor", "hdl64", "--foliage", "porous", "--out", tmp_path / "cli")
    for name in leafy["files"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    solid = quadrix.synth("street", seed=11, sensor="hdl64", primitives=False)
    vegetation = 70  # SemanticKITTI id, as the simulator labels crowns and hedges
    assert np.sum(leafy["clouds"][0].labels == vegetation) > 5 * np.sum(solid["clouds"][0].labels == vegetation)
    assert any(p["name"].startswith("hedge_") and p["mean_free_path"] > 0 for p in leafy["primitives"]["primitives"])
    with pytest.raises(ValueError, match="porous"):
        quadrix.synth("corridor", foliage="porous")
    with pytest.raises(ValueError, match="solid or porous"):
        quadrix.synth("street", foliage="leafy")


def test_out_folder_is_replaced_whole_and_a_foreign_one_is_refused(tmp_path):
    out = tmp_path / "py"
    quadrix.synth("corridor", seed=2, sensor="vlp16", primitives=False, out=out, poses="0,0,0,0;2,0,0,0;4,0,0,0")
    assert (out / "scan_002.ply").exists()
    # A second run writing two scans replaces the folder whole: no third scan of the first run stays.
    quadrix.synth("corridor", seed=2, sensor="vlp16", primitives=False, out=out)
    assert (out / "scan_001.ply").exists() and not (out / "scan_002.ply").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["py"], "no staging folder is left beside it"
    foreign = tmp_path / "thesis"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("not ours")
    with pytest.raises(ValueError, match="thesis.tex"):
        quadrix.synth("corridor", seed=2, sensor="vlp16", primitives=False, out=foreign)
    assert (foreign / "thesis.tex").read_text() == "not ours"
