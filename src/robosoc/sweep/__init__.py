"""Design-space exploration: run a sweep file's points on a local pool or a Dask cluster.

:mod:`~robosoc.sweep.plan` expands a sweep file into points, :mod:`~robosoc.sweep.point` runs
one point (in a worker), :mod:`~robosoc.sweep.store` keeps each finished point on disk so a
sweep resumes, :mod:`~robosoc.sweep.runner` drives the workers.
"""
