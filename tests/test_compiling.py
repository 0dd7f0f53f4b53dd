"""numba paid for only where it pays (ftlbo_mav/compiling.py): a long compile says so on
stderr before it starts, once; a short one says nothing."""

from __future__ import annotations

from ftlbo_mav import compiling


def test_a_long_compile_is_announced_once_before_it_starts(monkeypatch, tmp_path):
    said = []
    monkeypatch.setattr(compiling, "notify", said.append)
    monkeypatch.setattr(compiling, "_announced", set())
    monkeypatch.setenv(compiling.LOG_ENV, str(tmp_path / "compiles.log"))

    def long_loop(x):
        return x + 1.0

    def short_loop(x):
        return x - 1.0

    module = long_loop.__module__
    monkeypatch.setitem(compiling.WHAT, module, "the test's loops")
    monkeypatch.setitem(compiling.SECONDS, f"{module}.{long_loop.__qualname__}", 12.0)
    monkeypatch.setitem(compiling.SECONDS, f"{module}.{short_loop.__qualname__}", 0.2)
    short = compiling.njit(short_loop)
    assert short(1.0) == 0.0
    assert said == []  # under a second: compiled without a word
    long = compiling.njit(long_loop)
    assert not compiling.ready(long)
    assert long(1.0) == 2.0
    assert compiling.ready(long)  # compiled in this process
    assert len(said) == 1
    assert "compiling the test's loops" in said[0] and "about 12 s" in said[0]
    same = lambda x: x  # noqa: E731
    compiling.njit(same)(1.0)  # the module's later compiles: said once
    assert len(said) == 1
    logged = (tmp_path / "compiles.log").read_text().split()
    assert logged[0::2] == [f"{module}.{f.__qualname__}" for f in (short_loop, long_loop, same)]
    assert all(float(seconds) >= 0.0 for seconds in logged[1::2])


def test_a_plain_function_is_never_ready():
    assert not compiling.ready(lambda x: x)
