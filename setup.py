"""Build of the compiled visibility core (exactff.visibility._svbsp), of the area
code's hidden regions (exactff.area._hidden), of the unoccluded rows' sector sums
(exactff.kernel._sector) and of the discrete methods' z-buffer (exactff.methods._zbuffer);
the rest of the project's metadata is in pyproject.toml."""

import platform

from pybind11.setup_helpers import Pybind11Extension, build_ext
from setuptools import setup

# the quadruple-precision tier uses GCC's libquadmath on x86 (long double is already
# quadruple on aarch64)
QUADMATH = ["-lquadmath"] if platform.machine().lower() in ("x86_64", "amd64", "i686") else []

setup(
    ext_modules=[Pybind11Extension("exactff.visibility._svbsp",
                                   ["exactff/visibility/_svbsp.cpp",
                                    "exactff/visibility/_bsp_build.cpp"],
                                   cxx_std=17, extra_compile_args=["-O2"],
                                   extra_link_args=QUADMATH),
                 Pybind11Extension("exactff.area._hidden", ["exactff/area/_hidden.cpp"],
                                   depends=["exactff/kernel/_sector_term.h"], cxx_std=17,
                                   extra_compile_args=["-O3", "-fno-math-errno"]),
                 # the same arithmetic as kernel/sector.py's numpy: no contraction into
                 # fused multiply-adds, no reassociation
                 Pybind11Extension("exactff.kernel._sector", ["exactff/kernel/_sector.cpp"],
                                   depends=["exactff/kernel/_sector_term.h"], cxx_std=17,
                                   extra_compile_args=["-O3", "-fno-math-errno",
                                                       "-ffp-contract=off"]),
                 # no contraction into fused multiply-adds: the z-buffer mirrors the numpy
                 # rasteriser's expressions bit for bit
                 Pybind11Extension("exactff.methods._zbuffer", ["exactff/methods/_zbuffer.cpp"],
                                   cxx_std=17, extra_compile_args=["-O3", "-ffp-contract=off"])],
    cmdclass={"build_ext": build_ext},
)
