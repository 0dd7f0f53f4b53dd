"""Link faults: repeatable from the seed, at the asked rates."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.sim.faults import DUPLICATE_GAP_S, REORDER_HOLD_S, Faults, FaultyPipe


def pipe(**kw):
    base = {"loss": 0.0, "duplicate": 0.0, "reorder": 0.0, "latency_s": 0.0}
    return FaultyPipe(**{**base, **kw}, rng=np.random.default_rng(7))


def test_clean_pipe_passes_everything_at_once():
    p = pipe()
    assert [p.route(i) for i in range(3)] == [[(0.0, 0)], [(0.0, 1)], [(0.0, 2)]]


def test_rates_are_about_right_and_repeatable():
    routed = [pipe(loss=0.3, duplicate=0.05, reorder=0.1).route(i) for i in range(1)]
    p, q = pipe(loss=0.3, duplicate=0.05, reorder=0.1), pipe(loss=0.3, duplicate=0.05, reorder=0.1)
    a = [p.route(i) for i in range(4000)]
    assert a == [q.route(i) for i in range(4000)] and routed
    lost = sum(not r for r in a) / len(a)
    dup = sum(len(r) == 2 for r in a) / len(a)
    held = sum(bool(r) and r[0][0] == REORDER_HOLD_S for r in a) / len(a)
    assert 0.27 < lost < 0.33 and 0.025 < dup < 0.05 and 0.05 < held < 0.09


def test_latency_and_duplicate_gap():
    p = pipe(duplicate=1.0, latency_s=0.1)
    assert p.route("m") == [(0.1, "m"), (0.1 + DUPLICATE_GAP_S, "m")]


def test_faults_validate():
    with pytest.raises(ValueError, match="loss_up"):
        Faults(loss_up=1.5)
    with pytest.raises(ValueError, match="latency"):
        Faults(latency_s=-1)
