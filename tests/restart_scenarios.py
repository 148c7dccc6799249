"""Scenarios shared by the restart tests (tests/apps/restart_test.py through
the command line, tests/python/test_restart.py through the Python package):
floes on a spectral sea with waves and wind, colliding. Format with t_end (s)
and coupling (the [coupling] section's lines).
"""

WAVES = """
[run]
t_end = {t_end}
dt_max = 0.05
output_interval = 0.5

[sea]
model = "spectral"
dims = 2
size = [80.0, 80.0]
cells = [32, 32]
depth = 20.0

[sea.waves]
kind = "regular"
amplitude = 0.3
wavelength = 40.0
direction = 10.0

[coupling]
{coupling}

[forcing]
wind = [15.0, 2.0]

[[floes.floe]]
vertices = [[10, 10], [22, 10], [22, 20], [10, 20]]
velocity = [0.8, 0.0]
[[floes.floe]]
vertices = [[24, 11], [34, 12], [33, 21], [25, 20]]
[[floes.floe]]
vertices = [[40, 40], [52, 42], [50, 52], [41, 50]]
thickness = 1.5
"""
