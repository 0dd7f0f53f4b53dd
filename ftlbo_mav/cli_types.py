"""Option types of the command line: numbers that must be finite, ports, connection
strings, system id lists. Each converts and checks a value where it enters, so that no
command has to; the rules themselves live with what they describe (system ids and
connection strings in :mod:`ftlbo_mav.link.addresses`)."""

from __future__ import annotations

import math

import click

from .errors import BadInput

MAX_PORT = 65535


class FiniteFloat(click.FloatRange):
    """A :class:`click.FloatRange` that also refuses NaN and infinity."""

    def convert(self, value, param, ctx):
        number = click.FLOAT.convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return super().convert(number, param, ctx)


PORT = click.IntRange(0, MAX_PORT)
"""A TCP or UDP port number; 0 where the option says it means "any free" or "none"."""


class HostPort(click.ParamType):
    """``HOST:PORT`` with PORT in 1..65535 -> ``(host, port)``."""

    name = "HOST:PORT"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        host, _, port = str(value).rpartition(":")
        if not host or not port.isdigit() or not 1 <= int(port) <= MAX_PORT:
            self.fail(f"{value!r}: expected HOST:PORT with a port 1..{MAX_PORT}, "
                      "e.g. 127.0.0.1:14550", param, ctx)
        return host, int(port)


class LinkUrl(click.ParamType):
    """A pymavlink connection string (one or several separated by spaces), its port checked
    (:func:`~ftlbo_mav.link.addresses.check_url`)."""

    name = "URL"

    def convert(self, value, param, ctx):
        from .link.addresses import check_url

        option = param.opts[0] if param is not None and param.opts else "URL"
        try:
            for url in str(value).split():
                check_url(url, option=option)
        except BadInput as exc:
            self.fail(str(exc), param, ctx)
        return value


class SysidList(click.ParamType):
    """``1..3`` or ``1,2,5`` -> ``[1, 2, 3]``
    (:func:`~ftlbo_mav.link.addresses.parse_sysids`); the text is kept for messages."""

    name = "IDS"

    def convert(self, value, param, ctx):
        from .link.addresses import parse_sysids

        try:
            parse_sysids(str(value))
        except BadInput as exc:
            self.fail(str(exc), param, ctx)
        return str(value)


LINK_URL = LinkUrl()
SYSIDS = SysidList()
HOST_PORT = HostPort()
