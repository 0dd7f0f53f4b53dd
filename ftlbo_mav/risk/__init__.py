"""Fly a plan many times on the emulator before flying it once: the distribution of what
a flight keeps (clearance, separation, formation error), not one sample.

- :mod:`.conditions`: the conditions a flight is flown in, drawn from its seed (pure);
- :mod:`.stats`: what the flights say together, with confidence intervals (pure);
- :mod:`.flight`: one flight on the emulator as ``fly`` flies it (I/O);
- :mod:`.engine`: the flights as Dask tasks, on a local cluster or a running one;
- :mod:`.report`: risk.json, risk.md and the figures.
"""
