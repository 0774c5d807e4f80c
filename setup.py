"""Build of the compiled code: the library exactff/_core/ (headers and sources, one concept
per file; docs/explanation/layout.md) as Python extension modules, the visibility
core and the BSP build (exactff.visibility._svbsp), the area code's hidden regions
(exactff.area._hidden), an occluded pair's events and cells (exactff.area._pair), the
unoccluded area pairs in closed form (exactff.area._closed), an area row's blockers
(exactff.area._row_culling) and the unoccluded rows' sector sums
(exactff.kernel._sector); and the discrete methods' z-buffer (exactff.methods._zbuffer). The rest of the project's metadata is in pyproject.toml."""

import os
import platform

from pybind11.setup_helpers import Pybind11Extension, build_ext
from setuptools import setup

CORE = os.path.join("exactff", "_core")
# every header of the library: a module is rebuilt when any of them changes
HEADERS = sorted(os.path.join(CORE, f) for f in os.listdir(CORE) if f.endswith(".h"))


def core(*names):
    return [os.path.join(CORE, name) for name in names]


# One set of flags for the library's modules. -O3 -fno-math-errno: the optimiser may inline
# and vectorise and call sqrt as an instruction (no errno to set); neither reassociates nor
# changes a rounding, so the values are the same bit for bit as at -O2 (tools/core_bits.py
# compare), and the rows are as fast (docs/explanation/layout.md has the figures).
# -ffp-contract=off: no contraction of a * b + c into a fused multiply-add, which rounds
# once instead of twice: the sector sums mirror kernel/sector.py's numpy expression by
# expression (tests/test_unoccluded_compiled.py compares them bit for bit), the z-buffer
# mirrors the numpy rasteriser's (tests/test_compiled_discrete.py compares every cell),
# and the library's error bounds count a rounding per operation. (x86-64's baseline has no FMA
# instruction, so there it changes nothing; on aarch64 it keeps the same values.)
CORE_FLAGS = ["-O3", "-fno-math-errno", "-ffp-contract=off"]
# the quadruple-precision tier uses GCC's libquadmath on x86 (long double is already
# quadruple on aarch64)
QUADMATH = ["-lquadmath"] if platform.machine().lower() in ("x86_64", "amd64", "i686") else []

setup(
    ext_modules=[Pybind11Extension("exactff.visibility._svbsp",
                                   core("bind_svbsp.cpp", "core.cpp", "culling.cpp",
                                        "shadow_tree.cpp", "pieces.cpp", "integrate.cpp",
                                        "bounds.cpp", "bsp_build.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS,
                                   extra_link_args=QUADMATH),
                 Pybind11Extension("exactff.area._hidden", core("bind_hidden.cpp", "hidden.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS),
                 Pybind11Extension("exactff.area._pair", core("bind_pair.cpp", "pair.cpp", "curved.cpp", "levels.cpp", "hidden.cpp",
                                        "hidden_setup.cpp", "occluded_pair.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS),
                 Pybind11Extension("exactff.area._closed", core("bind_closed.cpp", "closed_form.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS),
                 Pybind11Extension("exactff.area._row_culling",
                                   core("bind_row_culling.cpp", "row_culling.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS),
                 Pybind11Extension("exactff.kernel._sector", core("bind_sector.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS),
                 Pybind11Extension("exactff.methods._zbuffer",
                                   core("bind_zbuffer.cpp", "zbuffer.cpp"),
                                   depends=HEADERS, cxx_std=17, extra_compile_args=CORE_FLAGS)],
    cmdclass={"build_ext": build_ext},
)
