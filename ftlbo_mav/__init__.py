"""ftlbo-mav: formation path planning for small UAV swarms and MAVLink mission tooling."""

__version__ = "0.1.0"
