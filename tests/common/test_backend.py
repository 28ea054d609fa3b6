"""``common.backend``'s process settings: memory freed by a large array stays in the process (so
that the next stage's blocks and factorisations reuse its pages), unless the user set glibc's
malloc options."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

# allocate 200 MB, free it; print whether the backend kept freed memory and the resident size
# [MB] with the array and after it was freed
PROBE = """
import numpy as np
from common import backend
def rss():
    return int(open("/proc/self/statm").read().split()[1]) * 4096 / 1e6
a = np.ones(200_000_000 // 8)
held = rss()
del a
print(backend.KEEPS_FREED_MEMORY, held, rss())
"""

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="glibc and /proc/self/statm"
)


def _probe(env: dict[str, str]) -> tuple[bool, float, float]:
    out = subprocess.run(
        [sys.executable, "-c", PROBE],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    return out[0] == "True", float(out[1]), float(out[2])


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    env.pop("GLIBC_TUNABLES", None)
    return env


def test_freed_memory_stays_in_the_process():
    kept, held, after = _probe(_clean_env())
    assert kept
    assert after > held - 20.0  # MB: the 200 MB stay resident


def test_the_users_malloc_options_are_left_alone():
    """With the user's MALLOC_MMAP_MAX_ the setting is not applied, and glibc's default returns
    the array's memory to the kernel (which is what the probe above tells apart)."""
    kept, held, after = _probe({**_clean_env(), "MALLOC_MMAP_MAX_": "65536"})
    assert not kept
    assert after < held - 150.0  # MB
