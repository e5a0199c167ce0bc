"""Physical constants and unit multipliers (SI)."""

from __future__ import annotations

import math

#: Speed of light in vacuum [m/s] (exact, SI 2019).
SPEED_OF_LIGHT = 299_792_458.0
#: Vacuum permeability [H/m] (CODATA 2018).
MU_0 = 1.25663706212e-6
#: Vacuum permittivity [F/m].
EPSILON_0 = 1.0 / (MU_0 * SPEED_OF_LIGHT**2)
#: Impedance of free space [ohm].
ETA_0 = MU_0 * SPEED_OF_LIGHT

GHz = 1e9
MHz = 1e6
nm = 1e-9
um = 1e-6
mm = 1e-3
cm = 1e-2

DEG = math.pi / 180.0
