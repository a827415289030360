"""connrl: Long-Ji Lin's thesis (CMU-CS-93-103, 1993) as reusable reinforcement-learning software."""

__version__ = "0.1.0"
