"""pmactl host tools: identification, evaluation and the ``pmactl`` command line.

Needs the ``host`` extra (scipy, matplotlib) for everything but ``pmactl --help``.
"""
