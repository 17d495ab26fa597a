"""Compatibility: the reports moved to :mod:`vibkit.diagnose.report` (this name keeps old scripts working)."""

from .diagnose.report import write_fleet_report, write_report

__all__ = ["write_report", "write_fleet_report"]
