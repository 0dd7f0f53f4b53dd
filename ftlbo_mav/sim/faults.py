"""Link faults for the emulator: loss, duplication, reordering, latency, silence.

:class:`Faults` is the plain description (a CLI option or a test parameter);
:class:`FaultyPipe` applies one direction of it to messages, deciding with an injected
``numpy.random.Generator`` so a seeded run is repeatable.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# A reordered message is held back this long, so those sent just after it overtake it.
REORDER_HOLD_S = 0.03
# A duplicate follows its original after this long (a radio retransmitting, a router loop).
DUPLICATE_GAP_S = 0.002


@dataclass(frozen=True)
class Faults:
    """What goes wrong on one vehicle's link. Probabilities are per message, 0..1.

    ``loss_up``: messages to the vehicle dropped; ``loss_down``: from the vehicle.
    ``duplicate`` / ``reorder``: each way. ``latency_s``: added one-way delay.
    ``silent``: the vehicle sends nothing and answers nothing (switched off, wrong link).
    ``mute``: it sends HEARTBEATs but stops answering the mission protocol.
    ``close_after_items``: after this many mission items received (MISSION_ITEM_INT) the
    vehicle drops its TCP client, as a radio out of range or a crashed SITL does: the
    link closes mid-upload; ``None``: never.
    ``mavlink1``: the vehicle's port speaks MAVLink 1 only (its SERIALn_PROTOCOL 1, a
    3DR Solo on its original firmware): it sends MAVLink 1 frames, none of a message whose
    id is over 255, and keeps to it whatever it receives (GCS_Common.cpp: only a
    SERIALn_PROTOCOL 2 port switches to MAVLink 2 on hearing it,
    MAVLINK_STATUS_FLAG_OUT_MAVLINK1).
    """

    loss_up: float = 0.0
    loss_down: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    latency_s: float = 0.0
    silent: bool = False
    mute: bool = False
    close_after_items: int | None = None
    mavlink1: bool = False

    def __post_init__(self) -> None:
        for name in ("loss_up", "loss_down", "duplicate", "reorder"):
            p = getattr(self, name)
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"{name} must be within 0..1, got {p}")
        if self.latency_s < 0:
            raise ValueError(f"latency_s must be >= 0, got {self.latency_s}")
        if self.close_after_items is not None and self.close_after_items < 0:
            raise ValueError(f"close_after_items must be >= 0, got {self.close_after_items}")


class FaultyPipe:
    """One direction of a link: ``route(payload)`` -> ``[(delay_s, payload), ...]``.

    An empty list is a lost message; two entries a duplicate; a delay beyond the base
    latency a message that later ones overtake.
    """

    def __init__(self, *, loss: float, duplicate: float, reorder: float, latency_s: float,
                 rng: np.random.Generator):
        self.loss, self.duplicate, self.reorder = loss, duplicate, reorder
        self.latency_s = latency_s
        self.rng = rng

    @classmethod
    def up(cls, faults: Faults, rng: np.random.Generator) -> FaultyPipe:
        return cls(loss=faults.loss_up, duplicate=faults.duplicate, reorder=faults.reorder,
                   latency_s=faults.latency_s, rng=rng)

    @classmethod
    def down(cls, faults: Faults, rng: np.random.Generator) -> FaultyPipe:
        return cls(loss=faults.loss_down, duplicate=faults.duplicate, reorder=faults.reorder,
                   latency_s=faults.latency_s, rng=rng)

    def route(self, payload):
        if self.loss and self.rng.random() < self.loss:
            return []
        delay = self.latency_s
        if self.reorder and self.rng.random() < self.reorder:
            delay += REORDER_HOLD_S
        out = [(delay, payload)]
        if self.duplicate and self.rng.random() < self.duplicate:
            out.append((delay + DUPLICATE_GAP_S, payload))
        return out
