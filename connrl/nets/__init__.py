"""Tiny per-sample networks of the thesis: symmetric-sigmoid MLPs, OAON, recurrent OAON (``recurrent``)."""

from connrl.nets.mlp import OAON, NetConfig, symmetric_sigmoid

__all__ = ["OAON", "NetConfig", "symmetric_sigmoid"]
