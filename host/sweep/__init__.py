"""``pmactl sweep``: regression matrices and parameter sweeps, locally or on a Ray cluster.

A matrix (:mod:`host.sweep.matrix`) expands into cells; each cell runs pmactl's own command
line in subprocesses (:mod:`host.sweep.runner`) on a backend (:mod:`host.sweep.backends`: an
embedded pool, or Ray tasks); :mod:`host.sweep.engine` retries, journals and resumes;
:mod:`host.sweep.report` writes the table and the pass/fail summary.
"""
