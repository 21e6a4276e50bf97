"""The README's snippets are the tested files (python/examples/register_pair.py and
tests/install/consumer/CMakeLists.txt, shown verbatim between their markers), and the Python
examples run."""
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import quadrix


def readme_block(source_dir, path, language):
    """The code block of README.md between `<!-- example: path -->` and `<!-- end example -->`."""
    readme = (source_dir / "README.md").read_text()
    marker = f"<!-- example: {path} -->"
    assert marker in readme, f"README.md lacks the marker {marker}"
    block = readme[readme.index(marker) : readme.index("<!-- end example -->", readme.index(marker))]
    opening = f"```{language}\n"
    assert opening in block, f"the block after {marker} is not a ```{language} block"
    return block[block.index(opening) + len(opening) : block.rindex("```")]


@pytest.mark.parametrize(
    "path, language",
    [("python/examples/register_pair.py", "python"), ("tests/install/consumer/CMakeLists.txt", "cmake")],
)
def test_the_readme_shows_the_tested_file_verbatim(source_dir, path, language):
    assert readme_block(source_dir, path, language) == (source_dir / path).read_text()


def run_example(source_dir, name, *arguments, cwd):
    # quadrix is a package (build/python/quadrix/__init__.py): its parent folder goes on the path.
    environment = dict(os.environ, PYTHONPATH=str(pathlib.Path(quadrix.__file__).parent.parent))
    return subprocess.run([sys.executable, str(source_dir / "python" / "examples" / name), *map(str, arguments)],
                          capture_output=True, text=True, cwd=cwd, env=environment)


def test_the_readme_example_registers_a_simulated_pair(source_dir, tmp_path, street):
    pair = street["pairs"][0]
    quadrix.write_cloud(tmp_path / "source.ply", street["clouds"][pair["source"]])
    quadrix.write_cloud(tmp_path / "target.ply", street["clouds"][pair["target"]])
    completed = run_example(source_dir, "register_pair.py", "source.ply", "target.ply", cwd=tmp_path)
    assert completed.returncode == 0, completed.stderr
    numbers = completed.stdout.replace("[", " ").replace("]", " ").split()[:16]
    transform = np.array([float(x) for x in numbers]).reshape(4, 4)
    assert np.linalg.norm(transform[:3, 3] - pair["transform"][:3, 3]) < 0.2
    assert "\nok " in completed.stdout


def test_the_plot_example_prints_the_report_and_saves_a_top_view(source_dir, tmp_path, shared_data):
    source = shared_data("kitti00/velodyne/000000.bin")
    target = shared_data("kitti00/velodyne/004438.ply")
    truth = shared_data("kitti00/gt/T_004438_from_000000.txt")
    picture = tmp_path / "top.png"
    completed = run_example(source_dir, "register_and_plot.py", source, target, "--gt", truth, "--out", picture,
                            cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert '"status": "ok"' in completed.stdout and '"success": true' in completed.stdout
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and picture.stat().st_size > 20000


def test_the_plot_example_runs_without_data(source_dir, tmp_path):
    completed = run_example(source_dir, "register_and_plot.py", "--out", tmp_path / "street.png", cwd=tmp_path)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert (tmp_path / "street.png").stat().st_size > 20000
