"""Tiny per-sample networks of the thesis: symmetric-sigmoid MLPs, OAON, recurrent OAON (``recurrent``)."""

from connrl.nets.mlp import OAON, NetConfig, symmetric_sigmoid
from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON

__all__ = ["OAON", "NetConfig", "RecurrentNetConfig", "RecurrentOAON", "symmetric_sigmoid"]
