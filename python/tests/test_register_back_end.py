"""quadrix.register for a back end: fitness, inlier RMSE, correspondences and the information matrix
(as Open3D and small_gicp return them), an initial guess and local-only registration, in Python and
in report.json."""
import json

import numpy as np
import pytest

import quadrix


def rotation_error_degrees(estimate, truth):
    cosine = (np.trace(estimate[:3, :3].T @ truth[:3, :3]) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def perturbed(transform, metres, degrees, seed):
    """``transform`` moved by exactly ``metres`` and turned by ``degrees`` about random axes, on the left."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    angle = np.radians(degrees)
    skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    delta = np.eye(4)
    delta[:3, :3] = np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew
    delta[:3, 3] = metres * direction
    return delta @ transform


def check_back_end_fields(result, source, target):
    pairs = result.correspondences
    assert pairs.dtype == np.int64 and pairs.ndim == 2 and pairs.shape[1] == 2 and len(pairs) > 0
    assert np.all(np.diff(pairs[:, 0]) > 0)  # each source point once
    assert pairs[:, 0].max() < len(source) and pairs[:, 1].max() < len(target)
    T = result.transform
    moved = source[pairs[:, 0]] @ T[:3, :3].T + T[:3, 3]
    distances = np.linalg.norm(moved - target[pairs[:, 1]], axis=1)
    assert distances.max() <= 0.3 + 1e-5
    assert result.inlier_rmse == pytest.approx(np.sqrt(np.mean(distances ** 2)), rel=1e-4)
    assert len(pairs) / len(source) <= result.fitness <= 1.0
    information = result.information
    assert information.shape == (6, 6)
    np.testing.assert_allclose(information, information.T, rtol=1e-9, atol=1e-9 * np.abs(information).max())
    eigenvalues = np.linalg.eigvalsh(information)
    assert eigenvalues[0] >= -1e-9 * eigenvalues[-1] and eigenvalues[-1] > 0
    report = result.report
    assert report["fitness"] == result.fitness and report["inlier_rmse_m"] == result.inlier_rmse
    assert report["correspondence_count"] == len(pairs)
    assert report["from_initial_guess"] == result.from_initial_guess
    assert np.array(report["information"]).shape == (6, 6)


@pytest.fixture(scope="module")
def street_pair(street):
    pair = street["pairs"][0]
    source, target = street["clouds"][pair["source"]], street["clouds"][pair["target"]]
    return np.asarray(source.points, dtype=np.float64), np.asarray(target.points, dtype=np.float64), pair["transform"]


def test_a_global_answer_has_fitness_correspondences_and_information(street_pair):
    source, target, truth = street_pair
    result = quadrix.register(source, target)
    assert result.ok, result.message
    assert not result.from_initial_guess
    check_back_end_fields(result, source, target)
    assert result.fitness > 0.3 and result.inlier_rmse < 0.15


def test_local_only_converges_from_a_guess_one_metre_and_five_degrees_off(street_pair):
    source, target, truth = street_pair
    result = quadrix.register(source, target, initial_guess=perturbed(truth, 1.0, 5.0, seed=5), local_only=True)
    assert result.ok, result.message
    assert result.from_initial_guess and result.candidates == []
    assert np.linalg.norm(result.transform[:3, 3] - truth[:3, 3]) < 0.1
    assert rotation_error_degrees(result.transform, truth) < 0.5
    check_back_end_fields(result, source, target)


def test_a_far_guess_loses_to_the_global_answer(street_pair):
    source, target, truth = street_pair
    result = quadrix.register(source, target, initial_guess=perturbed(truth, 15.0, 90.0, seed=6))
    assert result.ok, result.message
    assert not result.from_initial_guess
    assert np.linalg.norm(result.transform[:3, 3] - truth[:3, 3]) < 0.2


def test_information_follows_the_target_origin(street_pair):
    source, target, truth = street_pair
    # The same pair with the target's sensor 30 m away from its frame's origin: the answer and the
    # inliers are the same, the information is about the target frame given.
    origin = np.array([30.0, -20.0, 2.0])
    guess = perturbed(truth, 0.5, 2.0, seed=7)
    centred = quadrix.register(source, target, initial_guess=guess, local_only=True)
    shifted_guess = guess.copy()
    shifted_guess[:3, 3] += origin
    shifted = quadrix.register(source, target + origin, initial_guess=shifted_guess, local_only=True,
                               target_origin=origin)
    assert centred.ok and shifted.ok
    # The shifted target is stored in float32 far from its origin: a few points may pair differently.
    assert len(shifted.correspondences) == pytest.approx(len(centred.correspondences), rel=1e-2)
    # Recompute the information about the shifted origin from the rows (T s) x n, n: with p' = p + origin
    # the translation block is unchanged and the rotation block grows with the new lever arms.
    np.testing.assert_allclose(shifted.information[3:, 3:], centred.information[3:, 3:], rtol=2e-2)
    assert not np.allclose(shifted.information[:3, :3], centred.information[:3, :3], rtol=1e-2)


def test_local_only_needs_an_initial_guess(street_pair):
    source, target, _ = street_pair
    with pytest.raises(ValueError, match="initial_guess"):
        quadrix.register(source, target, local_only=True)


def test_the_command_line_takes_an_initial_guess(tmp_path, quadrix_cli, street):
    pair = street["pairs"][0]
    source, target = tmp_path / "source.ply", tmp_path / "target.ply"
    quadrix.write_cloud(source, street["clouds"][pair["source"]])
    quadrix.write_cloud(target, street["clouds"][pair["target"]])
    guess = tmp_path / "guess.txt"
    np.savetxt(guess, perturbed(pair["transform"], 1.0, 5.0, seed=8)[:3])  # 3x4, as KITTI writes poses
    quadrix_cli("register", source, target, "--initial-guess", guess, "--local", "--no-page", "--out", tmp_path / "out")
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["status"] == "ok" and report["from_initial_guess"] is True
    assert report["fitness"] > 0.3 and report["correspondence_count"] > 0
    assert np.array(report["information"]).shape == (6, 6)
    transform = np.array(report["transform"])
    assert np.linalg.norm(transform[:3, 3] - pair["transform"][:3, 3]) < 0.1
