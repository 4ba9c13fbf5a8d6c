"""The package's compiled part (everything else is declared in pyproject.toml): the CSV formatter
core.output._csvformat, compiled from Cython by ``pip install`` (build-system.requires)."""

from Cython.Build import cythonize
from setuptools import Extension, setup

setup(ext_modules=cythonize([Extension("core.output._csvformat", ["core/output/_csvformat.pyx"],
                                       extra_compile_args=["-O2"])],
                            compiler_directives={"language_level": 3}))
