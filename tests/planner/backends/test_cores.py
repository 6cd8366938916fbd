"""The planner shares its cores: llama.cpp's OpenMP threads spin briefly, then sleep, when they wait, unless the
user chose otherwise.

libgomp reports the settings it read when it was loaded (``omp_display_env``); a process that imports the planner
and then llama.cpp must have read the planner's short spin, where libgomp's own default spins 300,000 times at
every barrier and made two plans on 2 cores take 7 times one alone.
"""

from __future__ import annotations

import os
import subprocess
import sys

from smartllm_local.planner.backends.cores import SPINS, WAIT_SETTINGS, share_cores

_SHOW = ("import smartllm_local.planner, ctypes, llama_cpp; "
         "ctypes.CDLL('libgomp.so.1').omp_display_env(1)")


def _libgomp_settings(**settings: str) -> str:
    env = {k: v for k, v in os.environ.items() if k not in WAIT_SETTINGS} | settings
    done = subprocess.run([sys.executable, "-c", _SHOW], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stderr


def test_llama_cpps_threads_spin_briefly_once_the_planner_is_imported():
    assert f"GOMP_SPINCOUNT = '{SPINS}'" in _libgomp_settings() and int(SPINS) < 300_000


def test_a_users_own_wait_setting_is_kept():
    assert "OMP_WAIT_POLICY = 'ACTIVE'" in _libgomp_settings(OMP_WAIT_POLICY="ACTIVE")
    assert "GOMP_SPINCOUNT = '0'" in _libgomp_settings(OMP_WAIT_POLICY="PASSIVE")
    assert "GOMP_SPINCOUNT = '20000'" in _libgomp_settings(GOMP_SPINCOUNT="20000")


def test_share_cores_sets_a_short_spin_only_where_no_wait_was_chosen():
    env: dict[str, str] = {}
    assert share_cores(env) and env == {"GOMP_SPINCOUNT": SPINS}
    chosen = {"GOMP_SPINCOUNT": "5000"}
    assert not share_cores(chosen) and chosen == {"GOMP_SPINCOUNT": "5000"}
