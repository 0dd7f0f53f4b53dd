"""numba, paid for only where it pays: whether a compiled loop's machine code is at hand,
and a word on stderr before a long compile.

Every loop compiled here (:mod:`.ardupilot.compiled`, ``planning/_*_jit.py``,
``mission/_rally_jit.py``) has a numpy or stepwise twin that gives the same answer, and
each call site chooses between the two by the size of the work. What the compiled loop
costs to start is not one figure: some 0.3 s to import numba and load machine code
cached by an earlier run, but 10 s and more to compile it the first time after an
install or an upgrade (numba caches beside the source, or in its user cache when that is
read-only). So the call sites ask :func:`ready` where the twin is cheap, and a process
whose cache is cold keeps to the twin until the work outgrows the compile
(:data:`.ardupilot.flight_path.COLD_STEPWISE_UP_TO_S`); where only the compiled loop will
do (thousands of trees), :func:`announce_compiles` has numba's own compile event say so on
stderr before the compile starts, with what it compiles and about how long it takes.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

WHAT: dict[str, str] = {
    "ftlbo_mav.ardupilot.compiled": "the flown-path model",
    "ftlbo_mav.planning._geometric_jit": "the tangent graph's loops",
    "ftlbo_mav.planning._cost_jit": "the safety term",
    "ftlbo_mav.planning._proximity_jit": "the nearest-sample search",
    "ftlbo_mav.mission._rally_jit": "the rally search",
}
"""Per module of compiled loops: what it is, in the user's words."""

LATER: dict[str, str] = {
    "ftlbo_mav.planning._geometric_jit": "ftlbo_mav.planning.warm:compile_loops",
    "ftlbo_mav.planning._proximity_jit": "ftlbo_mav.planning.warm:compile_loops",
}
"""Per module whose loops :func:`cheap` runs only once cached: the function
(``"package.module:function"``) that compiles them in the background."""

SECONDS: dict[str, float] = {
    "ftlbo_mav.ardupilot.compiled.fly": 12.0,  # 11-12 s quiet, 20-26 s at load 5-7
    "ftlbo_mav.ardupilot.compiled._follow": 4.0,  # 4.1 and 6.0 s at load 6
    "ftlbo_mav.planning._cost_jit.safety": 3.0,  # 3.6 s at load 5
    "ftlbo_mav.planning._proximity_jit._nearest": 1.5,  # 1.9 s at load 5
    "ftlbo_mav.mission._rally_jit.clear_of_segments": 1.0,  # 1.3 s at load 5
    "ftlbo_mav.mission._rally_jit.first_clear": 2.5,  # 2.8 s at load 2
}
"""About how many seconds a loop (``module.function``) takes to compile on 2 quiet cores,
its callees with it (``python benchmarks/cold.py``, ``FTLBO_MAV_COMPILE_LOG``; the
machine measured on was shared: the figures in the comments). Under a second: compiled
without a word; a loop not here: the word without a figure."""

LOG_ENV = "FTLBO_MAV_COMPILE_LOG"
"""A file to which every compile of ours appends ``module.function seconds``
(``benchmarks/cold.py`` reads it)."""

notify: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
"""Where the word before a compile goes (stderr; tests may catch it)."""

BACKGROUND_ENV = "FTLBO_MAV_BACKGROUND_COMPILE"
"""Set to ``0`` and :func:`compile_later` starts nothing (the tests do: many processes)."""

_announced: set[str] = set()
_started_later: set[str] = set()
_depth = 0
_listening = False


def loaded() -> bool:
    """True when some part of this process has imported numba already."""
    return "numba" in sys.modules


def ready(*functions) -> bool:
    """True when every one of the numba ``functions`` has its machine code at hand: compiled
    in this process already, or cached by an earlier run for its source as it is now (then
    calling it costs a load, not a compile). False for anything numba would compile first,
    and for a plain function (numba not installed: the caller's twin is the right choice)."""
    for function in functions:
        if getattr(function, "signatures", None):
            continue
        try:  # numba's own cache index: empty when missing or made for other source
            if not function._cache._cache_file._load_index():
                return False
        except Exception:  # not a numba dispatcher, or a numba without this cache layout
            return False
    return True


def cheap(get: Callable[[], object]) -> bool:
    """Whether running compiled loops now costs next to nothing: numba is loaded in this
    process and the loop (or tuple of loops) ``get()`` returns is :func:`ready`. ``get``
    imports the loops' module, called only when numba is loaded (an import that would
    otherwise load it). When they are not ready and :data:`LATER` names how their module
    is compiled, that starts in the background (:func:`compile_later`): a run that would
    have used them finds them cached next time, instead of only after some plan large
    enough to compile them in the foreground."""
    if not loaded():
        return False
    loops = get()
    loops = loops if isinstance(loops, tuple) else (loops,)
    if ready(*loops):
        return True
    module = getattr(loops[0], "py_func", loops[0]).__module__
    if module in LATER:
        compile_later(module, LATER[module])
    return False


def compile_later(module: str, how: str) -> bool:
    """Start, once per process, a background process (lower priority, detached) that
    compiles the loops of ``module`` into numba's cache by calling ``how``
    (``"package.module:function"``, no arguments), so that this run goes on with the twin
    and the next one, or this one once the cache is there (:func:`ready` is asked again),
    runs compiled. Says so on stderr. Returns whether it started one."""
    if module in _started_later or os.environ.get(BACKGROUND_ENV, "1") == "0":
        return False
    _started_later.add(module)
    lock = _lock(how)
    if lock is None:  # another process of this install is compiling it now
        return False
    try:
        subprocess.Popen([sys.executable, "-m", __name__, how, "--lock", str(lock)],
                         stdin=subprocess.DEVNULL,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         start_new_session=True, preexec_fn=_lower_priority)
    except OSError:
        return False
    notify(f"ftlbo-mav: compiling {WHAT.get(module, module)} for this machine in the "
           "background, once after an install or upgrade; this run goes on without it")
    return True


LOCK_STALE_S = 600.0
"""A background compile's lock older than this is taken to be left by one that died."""


def _lock(how: str) -> Path | None:
    """A lock file for compiling ``how`` of this copy of the package, made here (None
    when another process holds it): one background compile at a time, however many
    processes (the Dask workers of ``risk``) find the cache cold together."""
    key = hashlib.sha1(f"{Path(__file__).resolve()} {how}".encode()).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"ftlbo-mav-compiling-{key}.lock"
    try:
        if time.time() - path.stat().st_mtime > LOCK_STALE_S:
            path.unlink(missing_ok=True)
    except OSError:
        pass
    try:
        os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except OSError:
        return None
    return path


def _lower_priority() -> None:
    os.nice(10)


def njit(*args, **kwargs):
    """numba's ``njit`` for the loops of this package, with :func:`announce_compiles`
    listening; without numba, the plain function (every caller has a twin for it)."""
    try:
        from numba import njit as numba_njit
    except ImportError:  # pragma: no cover - numba is a dependency
        return lambda f: f
    announce_compiles()
    return numba_njit(*args, **kwargs)


def announce_compiles() -> None:
    """Have numba's compile event (fired on a cache miss only, before the compile) say on
    stderr what is being compiled and about how long it takes, for a loop that takes a
    second or more (:data:`SECONDS`), once per module; nested compiles (a loop's callees)
    are part of the outer one. :func:`njit` calls it."""
    global _listening
    if _listening:
        return
    from numba.core import event

    class _Listener(event.Listener):
        started = 0.0

        def on_start(self, ev):
            global _depth
            _depth += 1
            if _depth == 1:
                self.started = time.perf_counter()
                _starting(ev.data["dispatcher"].py_func)

        def on_end(self, ev):
            global _depth
            _depth -= 1
            if _depth == 0 and os.environ.get(LOG_ENV):
                with open(os.environ[LOG_ENV], "a", encoding="utf-8") as log:
                    log.write(f"{_name(ev.data['dispatcher'])} "
                              f"{time.perf_counter() - self.started:.2f}\n")

    event.register("numba:compile", _Listener())
    _listening = True


def _name(dispatcher) -> str:
    function = dispatcher.py_func
    return f"{function.__module__}.{function.__qualname__}"


def _starting(function) -> None:
    module = function.__module__
    seconds = SECONDS.get(f"{module}.{function.__qualname__}")
    if (seconds is not None and seconds < 1.0) or module in _announced or module not in WHAT:
        return
    _announced.add(module)
    about = f"about {seconds:.0f} s on 2 cores; " if seconds else ""
    notify(f"ftlbo-mav: compiling {WHAT.get(module, module)} for this machine, once after "
           f"an install or upgrade ({about}later runs load it from the cache)")


def main(argv: list[str]) -> int:
    """``python -m ftlbo_mav.compiling package.module:function [--lock FILE]``: what
    :func:`compile_later` runs in the background (and the lock it removes when done)."""
    import importlib

    os.environ[BACKGROUND_ENV] = "0"
    lock = None
    if "--lock" in argv:
        at = argv.index("--lock")
        lock, argv = Path(argv[at + 1]), argv[:at] + argv[at + 2:]
    try:
        for how in argv:
            module, _, function = how.partition(":")
            getattr(importlib.import_module(module), function)()
    finally:
        if lock is not None:
            lock.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
