"""Allocator tuning (core.util.memory): glibc accepts both settings; without mallopt it is a no-op."""

from __future__ import annotations

import ctypes
import platform
import subprocess
import sys

import pytest

from core.util import memory


@pytest.mark.skipif(platform.system() != "Linux" or platform.libc_ver()[0] != "glibc", reason="glibc only")
def test_glibc_accepts_the_settings():
    code = "from core.util import memory; print(memory.tune_allocator())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["True"]


def test_no_mallopt_is_a_no_op(monkeypatch):
    def no_libc(name):
        raise OSError("no C library here")

    monkeypatch.setattr(ctypes, "CDLL", no_libc)
    assert memory.tune_allocator() is False
