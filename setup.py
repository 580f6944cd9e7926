"""Builds the C++ module flatsos._flatsos with CMake for the interpreter that runs pip, then lets
setuptools package it beside the pure-Python modules of python/flatsos.

FLATSOS_BUILD_DIR names a CMake build of this source tree to reuse (its _flatsos target is
brought up to date); otherwise a build without tests or programs is made in build-pip/."""
import os
import pathlib
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE_DIR = pathlib.Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR") or PIP_BUILD_DIR / "cmake")
        if not (build_dir / "CMakeCache.txt").exists():
            subprocess.check_call(["cmake", "-S", str(SOURCE_DIR), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                                   "-DFLATSOS_BUILD_TESTS=OFF", "-DFLATSOS_BUILD_EXAMPLES=OFF",
                                   "-DFLATSOS_BUILD_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}"])
        jobs = str(os.cpu_count() or 1)
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "_flatsos", "-j", jobs])
        built = sorted((build_dir / "python" / "flatsos").glob("_flatsos*.so"))
        if not built:
            raise RuntimeError(f"{build_dir}: the CMake build made no python/flatsos/_flatsos*.so")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[-1], target)


# Kept out of build/, the CMake build folder of the README's commands: setuptools' build/lib would
# otherwise meet CMake's static libraries there.
PIP_BUILD_DIR = SOURCE_DIR / "build-pip"
PIP_BUILD_DIR.mkdir(exist_ok=True)
setup(ext_modules=[CMakeExtension("flatsos._flatsos")], cmdclass={"build_ext": CMakeBuild},
      options={"build": {"build_base": str(PIP_BUILD_DIR)}, "egg_info": {"egg_base": str(PIP_BUILD_DIR)}})
