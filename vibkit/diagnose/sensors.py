"""Which sensor a channel is: what a diagnosis may assume about where a channel's signal comes from.

A channel's sensor is data, never a guess from its unit's spelling.  :func:`channel_sensor` takes it, in this
order, from

1. the escalator profile's entry for the channel, ``[sensors.NAME]`` (``kind`` "tensioner", "step" or "phone");
2. the quantity the reader measured it as (the channel's ``quantity`` attribute; a recording made without a reader,
   such as vibkit's own simulation, states its unit only, which the io layer's unit table turns into its quantity):
   a displacement is the tensioner's sensor, fixed beside the chain;
3. the profile's single ``[sensor]``, the default of every channel that is not a displacement;
4. else nothing is known: vibkit's simulated step channel ``accel_step`` rides a step, any other channel is
   ``"unknown"``.

:class:`ChannelSensor` answers the two questions the diagnoses ask: whether the channel rides a step (``vibkit
pitch`` then warns that a step's link pass reads off the chain's) and whether it is the tensioner's displacement
(the sensor the worn link's signature is known for, :data:`SIGNATURES`).  A unit with a tensioner displacement and a
phone on a step is described by ``[sensors.<tensioner channel>] kind = "tensioner"`` and ``[sensor] kind = "phone"``
(or one ``[sensors.NAME]`` each): each channel's warning is then its own.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..io.text.units import parse_unit
from ..model.profile import STEP_KINDS

__all__ = [
    "SIGNATURES",
    "ChannelSensor",
    "channel_quantity",
    "channel_sensor",
    "channel_sensors",
    "is_acceleration_channel",
    "is_tensioner_channel",
]

#: sensor kind -> the model output its worn-link signature is simulated as (the tensioner's carriage: delta)
SIGNATURES = {"tensioner": "delta"}
#: a channel whose sensor nothing states: vibkit's simulated step accelerometer rides a step
SIMULATED_STEP_CHANNEL = "accel_step"


@dataclass(frozen=True)
class ChannelSensor:
    """The sensor of one channel: ``kind`` ("tensioner", "step", "phone" or "unknown"), the ``quantity`` the channel
    measures ("displacement", "velocity", "acceleration" or "other"), and ``source`` (what said so)."""

    channel: str
    kind: str
    quantity: str
    source: str
    step: int | None = None

    @property
    def rides_step(self) -> bool:
        """Whether the sensor rides a step (a step's link pass reads up to about 1 % off the chain's)."""
        return self.kind in STEP_KINDS

    @property
    def is_tensioner(self) -> bool:
        """Whether the channel is the tensioner's displacement, the sensor the worn link's signature is known for."""
        return self.kind == "tensioner" and (self.quantity == "displacement" or self.source.startswith("sensors."))

    @property
    def signature(self) -> str | None:
        """The model output the worn link's signature is simulated as for this sensor (:data:`SIGNATURES`), None
        where no signature is known."""
        return SIGNATURES.get(self.kind) if self.is_tensioner else None


def channel_quantity(recording, channel) -> str:
    """What the channel measures: its ``quantity`` attribute as the reader set it, else the quantity of its unit
    (:func:`vibkit.io.text.units.parse_unit`), else "other"."""
    attrs = recording[channel].attrs
    q = str(attrs.get("quantity", "") or "")
    if q and q != "other":
        return q
    unit = parse_unit(str(attrs.get("units", "") or ""))
    return unit.quantity if unit is not None else (q or "other")


def channel_sensor(recording, channel, profile=None) -> ChannelSensor:
    """The sensor of ``channel`` (see the module doc for the order: the profile's ``[sensors.NAME]``, the channel's
    quantity, the profile's ``[sensor]``, the simulated step's name)."""
    name = str(channel)
    quantity = channel_quantity(recording, name)
    own = (getattr(profile, "sensors", None) or {}).get(name)
    if own is not None:
        return ChannelSensor(name, own.kind, quantity, f"sensors.{name} of {profile.source}", own.step)
    if quantity == "displacement":
        return ChannelSensor(name, "tensioner", quantity, "the channel is a displacement")
    default = getattr(profile, "sensor", None)
    if default is not None:
        return ChannelSensor(name, default.kind, quantity, f"sensor of {profile.source}", default.step)
    if name == SIMULATED_STEP_CHANNEL:
        return ChannelSensor(name, "step", quantity, "vibkit's simulated step channel")
    return ChannelSensor(name, "unknown", quantity, "not stated")


def channel_sensors(recording, channels, profile=None) -> dict[str, ChannelSensor]:
    """:func:`channel_sensor` of each of ``channels`` present in ``recording``."""
    return {str(c): channel_sensor(recording, c, profile) for c in channels if c in recording}


def is_tensioner_channel(recording, channel, profile=None) -> bool:
    """Whether ``channel`` is the tensioner's displacement (:attr:`ChannelSensor.is_tensioner`)."""
    return channel_sensor(recording, channel, profile).is_tensioner


def is_acceleration_channel(recording, channel) -> bool:
    """Whether ``channel`` measures an acceleration (a step's accelerometer or a phone)."""
    return channel_quantity(recording, channel) == "acceleration"
