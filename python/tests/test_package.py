"""The package around the extension: type stubs that match it, a sentence naming the interpreter
the module was built for when another one imports it, one spelling (center) and one rotation format
(quaternion, with matrices beside), plain shape parameters, and the same model from the CLI and
from Python on the same file (the library's preset resolution, auto by default)."""
import ast
import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import quadrix


def test_the_stubs_declare_exactly_the_public_names_of_the_module():
    stub = pathlib.Path(quadrix.__file__).with_name("__init__.pyi")
    assert stub.exists(), "type stubs are generated beside the package"
    assert pathlib.Path(quadrix.__file__).with_name("py.typed").exists()
    tree = ast.parse(stub.read_text())
    declared = {node.name for node in tree.body if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    declared |= {node.target.id for node in tree.body if isinstance(node, ast.AnnAssign)}
    public = {name for name in dir(quadrix._extension) if not name.startswith("_")} | {"__version__"}
    assert declared == public
    model = next(node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == "Model")
    members = {node.name for node in model.body if isinstance(node, ast.FunctionDef)}
    assert {"center", "rotation", "rotation_matrix", "shapes", "save"} <= members
    register = next(node for node in tree.body if isinstance(node, ast.FunctionDef) and node.name == "register")
    assert [a.arg for a in register.args.args][:3] == ["source", "target", "preset"]


def test_another_interpreter_gets_a_sentence_naming_the_one_it_was_built_for():
    built = quadrix._BUILT_FOR_EXECUTABLE
    sentence = quadrix._interpreter_problem((3, 99, 0), "/opt/conda/bin/python3")
    assert built in sentence and "Python 3.99" in sentence and "/opt/conda/bin/python3" in sentence
    assert quadrix._interpreter_problem(sys.version_info, sys.executable) is None
    # An interpreter of the right version without NumPy: the import itself says what to do.
    completed = subprocess.run(
        [sys.executable, "-c", "import sys; sys.modules['numpy'] = None; import quadrix"],
        capture_output=True, text=True)
    assert completed.returncode != 0
    last = completed.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: quadrix needs NumPy") and built in last, completed.stderr


def test_one_spelling_and_one_rotation_format(street):
    model = quadrix.model(street["clouds"][0], preset="vlp64")
    np.testing.assert_array_equal(model.center, model.centre)  # the old spelling stays as an alias
    matrices = model.rotation_matrix
    assert matrices.shape == (len(model), 3, 3)
    w, x, y, z = model.rotation.T
    expected_first_column = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=1)
    np.testing.assert_allclose(matrices[:, :, 0], expected_first_column, atol=1e-9)
    records = json.loads(model.to_json())["quadrics"]
    np.testing.assert_allclose(np.array([r["rotation_matrix"] for r in records]).reshape(-1, 3, 3), matrices, atol=1e-12)
    assert "center" in records[0] and "centre" not in records[0]
    fitted = quadrix.fit(street["clouds"][0].points[:200], type="plane")
    assert len(fitted["rotation"]) == 4 and len(fitted["rotation_matrix"]) == 9 and "center" in fitted


def test_every_record_has_its_plain_shape_parameters(street):
    model = quadrix.model(street["clouds"][0], preset="vlp64")
    shapes = model.shapes
    assert len(shapes) == len(model)
    for kind, shape, center in zip(model.types, shapes, model.center):
        if kind == "plane":
            normal = np.array(shape["normal"])
            assert abs(np.linalg.norm(normal) - 1) < 1e-9
            assert abs(normal @ center + shape["offset"]) < 1e-3  # the record's center lies on its plane
        elif kind == "point":
            np.testing.assert_array_equal(shape["position"], center)
        elif kind in ("circular_cylinder", "sphere"):
            assert shape["radius"] > 0
    assert model.shapes == [r["shape"] for r in json.loads(model.to_json())["quadrics"]]


def test_cli_and_python_give_the_same_model_by_default(tmp_path, street, quadrix_cli):
    # Both resolve the preset as the library does (auto, measured on the cloud, by default).
    cloud = tmp_path / "scan.ply"
    quadrix.write_cloud(cloud, street["clouds"][0])
    out = tmp_path / "model.json"
    quadrix_cli("model", cloud, "--no-page", "--out", out)
    printed = json.loads(out.read_text())
    from_python = quadrix.model(cloud)
    assert printed["stats"]["preset_requested"] == "auto"
    assert len(printed["quadrics"]) == len(from_python)
    np.testing.assert_allclose(np.array([r["record"] for r in printed["quadrics"]]), from_python.records, rtol=0, atol=1e-9)
    assert printed["ground"]["found"] == from_python.ground["found"]
    np.testing.assert_allclose(printed["ground"]["normal"], from_python.ground["normal"], atol=1e-12)
    ground_points = [r["points"] for r in printed["quadrics"] if r["class"] == "ground"]
    python_ground = [int(n) for n, c in zip(from_python.point_counts, from_python.classes) if c == "ground"]
    assert ground_points == python_ground
