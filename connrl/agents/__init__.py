"""Agents of the thesis behind one protocol: ``begin_trial``, ``act``, ``observe``, ``end_trial``, ``learn``."""

from connrl.agents.ahcon import AHCON, AHCONConfig
from connrl.agents.base import Agent, LinearSchedule, ReplayConfig
from connrl.agents.qcon import QCON, QCONConfig

__all__ = ["AHCON", "AHCONConfig", "Agent", "LinearSchedule", "QCON", "QCONConfig", "ReplayConfig"]
