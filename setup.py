"""Builds the Python module cwloc for `pip install .` with CMake: the extension and
libcwloc.so, which goes into the package next to it (CWLOC_PYTHON_BUNDLE_LIB). docs/python.md
has the offline command. Everything else about the build is CMake's (python/CMakeLists.txt)."""
import os
import re
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
VERSION = re.search(r"project\(cwloc VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())[1]


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = Path(self.build_temp).resolve() / "cmake"
        package = Path(self.get_ext_fullpath(ext.name)).resolve().parent
        generator = ["-G", "Ninja"] if subprocess.run(
            ["ninja", "--version"], capture_output=True).returncode == 0 else []
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), *generator,
                        "-DCMAKE_BUILD_TYPE=Release", f"-DPython3_EXECUTABLE={sys.executable}",
                        "-DCWLOC_WITH_PYTHON=ON", "-DCWLOC_PYTHON_BUNDLE_LIB=ON",
                        "-DCWLOC_PYTHON_INSTALL_DIR=.", "-DCWLOC_BUILD_TESTS=OFF",
                        "-DCWLOC_BUILD_BENCHMARKS=OFF", "-DCWLOC_BUILD_TOOLS=OFF"], check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", "cwloc_python", "-j", jobs],
                       check=True)
        subprocess.run(["cmake", "--install", str(build), "--component", "python", "--prefix",
                        str(package.parent)], check=True)


setup(
    version=VERSION,
    packages=["cwloc"],
    package_dir={"cwloc": "python/cwloc"},
    package_data={"cwloc": ["py.typed", "*.pyi"]},
    ext_modules=[Extension("cwloc._cwloc", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # Not build/: that is the CMake build folder of the README.
    options={"build": {"build_base": "build-pip"}},
)
