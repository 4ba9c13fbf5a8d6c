"""The package's compiled parts (everything else is declared in pyproject.toml): the CSV formatter
core.output._csvformat, the segment-to-mesh distances core.paths._meshdist, the time-optimal solver's
passes core.machine._optimum, and verify's own table reader core.verify._tables, distance engine
core.verify._distance (its index built by core.verify._index) and forward kinematics
core.verify._axes, compiled from Cython by ``pip install`` (build-system.requires)."""

from Cython.Build import cythonize
from setuptools import Extension, setup

setup(ext_modules=cythonize([Extension("core.output._csvformat", ["core/output/_csvformat.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.paths._meshdist", ["core/paths/_meshdist.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.machine._optimum", ["core/machine/_optimum.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.verify._tables", ["core/verify/_tables.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.verify._distance", ["core/verify/_distance.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.verify._index", ["core/verify/_index.pyx"],
                                       extra_compile_args=["-O2"]),
                             Extension("core.verify._axes", ["core/verify/_axes.pyx"],
                                       extra_compile_args=["-O2"])],
                            compiler_directives={"language_level": 3}))
