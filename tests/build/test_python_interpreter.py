"""The Python tests run one interpreter: configuring for one that cannot import numpy stops with one
line that names it and the way out, instead of a suite whose Python tests all fail at `import
numpy`. ctest runs this with pytest (VKRAY_SOURCE_DIR from tests/CMakeLists.txt); the build folder is
a temporary one."""
import os
import stat
import subprocess
import sys

SOURCE = os.environ["VKRAY_SOURCE_DIR"]


def test_an_interpreter_without_numpy_is_refused_when_configuring(tmp_path):
    # The interpreter the suite runs under, with a numpy that cannot be imported first on its path.
    hidden = tmp_path / "hide" / "numpy"
    hidden.mkdir(parents=True)
    (hidden / "__init__.py").write_text("raise ImportError('numpy hidden by the test')\n")
    python = tmp_path / "python3"
    python.write_text(f"#!/bin/sh\nPYTHONPATH={tmp_path / 'hide'} exec {sys.executable} \"$@\"\n")
    python.chmod(python.stat().st_mode | stat.S_IXUSR)
    result = subprocess.run(["cmake", "-S", SOURCE, "-B", str(tmp_path / "build"), f"-DPython3_EXECUTABLE={python}"],
                            capture_output=True, text=True)
    assert result.returncode != 0
    said = " ".join(result.stderr.split())  # CMake wraps its messages
    assert f"vkray: the Python tests run {python}, which cannot import numpy" in said, result.stderr
    assert "-DPython3_EXECUTABLE=" in said
