"""Build of the compiled visibility core (exactff.visibility._svbsp); the rest of the
project's metadata is in pyproject.toml."""

from pybind11.setup_helpers import Pybind11Extension, build_ext
from setuptools import setup

setup(
    ext_modules=[Pybind11Extension("exactff.visibility._svbsp",
                                   ["exactff/visibility/_svbsp.cpp"],
                                   cxx_std=17, extra_compile_args=["-O2"])],
    cmdclass={"build_ext": build_ext},
)
