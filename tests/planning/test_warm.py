"""planning/warm.py: the loops a plan runs compiled only once cached get cached in the
background, through the calls a plan makes."""

from __future__ import annotations

import numba  # noqa: F401  (cheap() asks only once numba is loaded)

from ftlbo_mav import compiling
from ftlbo_mav.planning import discs, geometric, proximity, warm


def test_loops_not_cached_are_compiled_later_and_not_used_now(monkeypatch):
    started = []
    monkeypatch.setattr(compiling, "ready", lambda *loops: False)
    monkeypatch.setattr(compiling, "compile_later",
                        lambda module, how: started.append((module, how)) or True)
    assert not compiling.cheap(geometric._graph_loops)
    assert not compiling.cheap(proximity._compiled_nearest)
    assert not compiling.cheap(discs._rim_discs)  # (compile_later starts one a module)
    how = "ftlbo_mav.planning.warm:compile_loops"
    assert started == [("ftlbo_mav.planning._geometric_jit", how),
                       ("ftlbo_mav.planning._proximity_jit", how),
                       ("ftlbo_mav.planning._geometric_jit", how)]


def test_loops_cached_are_used_and_nothing_is_started(monkeypatch):
    monkeypatch.setattr(compiling, "ready", lambda *loops: True)
    monkeypatch.setattr(compiling, "compile_later", lambda module, how: 1 / 0)
    assert compiling.cheap(geometric._graph_loops)


def test_compile_loops_leaves_every_loop_ready_and_the_thresholds_as_they_were():
    before = (geometric.ARRAY_GRAPH_FROM, discs.COMPILED_RIM_FROM, proximity.FULL_ARRAY_LIMIT)
    for how in set(compiling.LATER.values()):
        module, _, function = how.partition(":")
        assert module == warm.__name__ and getattr(warm, function) is warm.compile_loops
    warm.compile_loops()
    assert (geometric.ARRAY_GRAPH_FROM, discs.COMPILED_RIM_FROM,
            proximity.FULL_ARRAY_LIMIT) == before
    assert compiling.ready(*geometric._graph_loops(), discs._rim_discs(),
                           proximity._compiled_nearest())
