"""ArduPilot SITL copters for ftlbo-mav: N instances, system ids 1..N, homes at the UAV starts.

``SitlSwarm`` is a context manager that owns the processes; ``python -m sitl`` starts a
swarm from the command line. See launcher.py.
"""

from .launcher import SitlSwarm, sitl_command

__all__ = ["SitlSwarm", "sitl_command"]
