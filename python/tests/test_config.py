"""quadrix.config and config dicts: the YAML schema as dicts, errors naming the key or the file."""
import numpy as np
import pytest

import quadrix


def flatten(section, prefix=""):
    """{dotted path: value} of nested dicts."""
    flat = {}
    for name, value in section.items():
        path = f"{prefix}.{name}" if prefix else name
        if isinstance(value, dict):
            flat.update(flatten(value, path))
        else:
            flat[path] = value
    return flat


def test_config_lists_every_key_of_the_schema_in_order():
    options = quadrix.config("vlp64")
    assert list(flatten(options)) == list(quadrix.config_keys())
    assert options["sensor"] == "vlp64"
    assert "extraction.planes.voxel_size" in quadrix.config_schema()
    assert quadrix.presets()[-1] == "auto" and "vlp16" in quadrix.presets()


def test_presets_differ_where_the_readme_says():
    vlp64, vlp16 = quadrix.config("vlp64"), quadrix.config("vlp16")
    assert vlp64["extraction"]["planes"]["voxel_size"] == pytest.approx(1.0)
    assert vlp16["extraction"]["planes"]["voxel_size"] == pytest.approx(1.4)


def test_a_config_dict_reproduces_the_preset_it_was_read_from():
    vlp16 = quadrix.config("vlp16")
    assert quadrix.config("vlp64", config=vlp16) == vlp16


def test_the_cli_yaml_and_the_dict_agree(tmp_path, quadrix_cli):
    path = tmp_path / "vlp16.yaml"
    path.write_text(quadrix_cli("config", "--preset", "vlp16"))
    assert quadrix.config("vlp64", config=path) == quadrix.config("vlp16")


def test_a_dict_override_sets_that_key_only():
    changed = quadrix.config("vlp64", config={"matching": {"thresholds": [0.3, 0.5]}, "estimation": {"refiner": "nlopt"}})
    reference = flatten(quadrix.config("vlp64"))
    flat = flatten(changed)
    assert flat["matching.thresholds"] == [0.3, 0.5]
    assert flat["estimation.refiner"] == "nlopt"
    differing = {key for key in reference if reference[key] != flat[key]}
    assert differing == {"matching.thresholds", "estimation.refiner"}


def test_unknown_key_in_a_dict_is_key_error_naming_it():
    with pytest.raises(KeyError, match="extraction.planes.voxel_sise"):
        quadrix.config("vlp64", config={"extraction": {"planes": {"voxel_sise": 1.0}}})
    with pytest.raises(KeyError, match="no_such_section"):
        quadrix.register(np.zeros((10, 3)), np.zeros((10, 3)), preset="vlp64", config={"no_such_section": 1})


def test_bad_value_in_a_dict_is_value_error_naming_the_key():
    with pytest.raises(ValueError, match="matching.thresholds"):
        quadrix.config("vlp64", config={"matching": {"thresholds": [0.5, 0.2]}})
    with pytest.raises(ValueError, match="estimation.refiner"):
        quadrix.config("vlp64", config={"estimation": {"refiner": "gauss"}})


def test_bad_files_name_the_file(tmp_path):
    unknown = tmp_path / "unknown.yaml"
    unknown.write_text("extraction:\n  planes:\n    voxel_sise: 1.0\n")
    with pytest.raises(ValueError, match="unknown.yaml.*voxel_sise"):
        quadrix.config("vlp64", config=str(unknown))
    broken = tmp_path / "broken.yaml"
    broken.write_text("matching: [unclosed\n")
    with pytest.raises(ValueError, match="broken.yaml"):
        quadrix.config("vlp64", config=broken)
    with pytest.raises(FileNotFoundError, match="absent.yaml"):
        quadrix.config("vlp64", config=tmp_path / "absent.yaml")


def test_unknown_preset_is_a_value_error():
    with pytest.raises(ValueError, match="vlp32"):
        quadrix.config("vlp32")


def test_auto_without_cloud_gives_the_defaults_it_starts_from():
    # As bare `quadrix config`: the preset auto falls back to for a cloud with nothing to measure.
    options = quadrix.config()
    assert options == quadrix.config("auto")
    assert options["sensor"] in quadrix.presets()
    assert options == quadrix.config(options["sensor"])


def test_auto_measures_the_cloud(street):
    options = quadrix.config("auto", cloud=street["clouds"][0])
    assert options["sensor"] in quadrix.presets()
