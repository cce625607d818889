"""snowjax: differentiable, batched wheel-on-snow terramechanics in JAX.

The physics follows Sankapalli (2004), *Predictive semi-empirical analysis for tire/snow
interaction* (MSc thesis, University of Alaska Fairbanks).  SI units throughout.
"""

from ._params import BekkerSoil as BekkerSoil
from ._params import RigidWheel as RigidWheel
from ._params import WongSnow as WongSnow
from ._terrain import bekker_pressure as bekker_pressure
from ._terrain import gawwad_crolla_shear as gawwad_crolla_shear
from ._terrain import gawwad_crolla_unloading_pressure as gawwad_crolla_unloading_pressure
from ._terrain import janosi_hanamoto as janosi_hanamoto
from ._terrain import mohr_coulomb as mohr_coulomb
from ._terrain import reece_pressure as reece_pressure
from ._terrain import wong_pressure as wong_pressure
from ._terrain import wong_sinkage as wong_sinkage

# --- wheel (chapter 4) ---

# --- tire (chapter 3) ---

# --- empirical (chapter 2) ---

__version__ = "0.1.0"
