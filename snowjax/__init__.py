"""snowjax: differentiable, batched wheel-on-snow terramechanics in JAX.

The physics follows Sankapalli (2004), *Predictive semi-empirical analysis for tire/snow
interaction* (MSc thesis, University of Alaska Fairbanks).  SI units throughout.
"""

# --- terrain laws ---

from ._terrain.bekker import BekkerSoil as BekkerSoil
from ._constants import DEFAULT_SHEAR_MODULUS as DEFAULT_SHEAR_MODULUS
from ._terrain.layered import LayeredSnow as LayeredSnow
from ._terrain.rut import Rut as Rut
from ._terrain.rut_map import RutMap as RutMap
from ._terrain.reece import ReeceSoil as ReeceSoil
from ._wheel.geometry import RigidWheel as RigidWheel
from ._wheel.geometry import AbstractWheel as AbstractWheel
from ._wheel.geometry import AbstractContact as AbstractContact
from ._wheel.geometry import ContactPoints as ContactPoints
from ._wheel.geometry import RimContact as RimContact
from ._wheel.tire import DeflectingTire as DeflectingTire
from ._leaves import ParameterInfo as ParameterInfo
from ._leaves import as_float as as_float
from ._leaves import parameter as parameter
from ._terrain.base import AbstractTerrain as AbstractTerrain
from ._terrain.base import Terrain as Terrain
from ._terrain.wong import WongSnow as WongSnow
from ._wheel.distribution import AbstractStressDistribution as AbstractStressDistribution
from ._wheel.distribution import FrontRegion as FrontRegion
from ._wheel.distribution import WongReece as WongReece
from ._wheel.lateral import Lateral as Lateral
from ._wheel.model import ContactModel as ContactModel
from ._wheel.terms import AbstractForceTerm as AbstractForceTerm
from ._wheel.terms import ContactNodes as ContactNodes
from ._wheel.terms import Resultants as Resultants
from ._wheel.shear_law import AbstractShearLaw as AbstractShearLaw
from ._wheel.shear_law import JanosiHanamoto as JanosiHanamoto
from ._wheel.shear_law import NoShear as NoShear
from ._wheel.shear_law import ThesisSimplified as ThesisSimplified
from ._terrain.bekker import bekker_pressure as bekker_pressure
from ._terrain.shear import gawwad_crolla_shear as gawwad_crolla_shear
from ._terrain.shear import gawwad_crolla_unloading_pressure as gawwad_crolla_unloading_pressure
from ._terrain.shear import janosi_hanamoto as janosi_hanamoto
from ._terrain.shear import mohr_coulomb as mohr_coulomb
from ._terrain.reece import reece_pressure as reece_pressure
from ._terrain.wong import wong_pressure as wong_pressure
from ._terrain.wong import wong_sinkage as wong_sinkage

# --- wheel (chapter 4) ---
from ._wheel.contact import ContactForces as ContactForces
from ._wheel.contact import contact_forces as contact_forces
from ._wheel.geometry import max_sinkage as max_sinkage
from ._wheel.contact import normal_stress as normal_stress
from ._wheel.geometry import rim_sinkage as rim_sinkage
from ._wheel.geometry import shear_displacement as shear_displacement
from ._wheel.contact import shear_stress as shear_stress
from ._wheel.equilibrium import Status as Status
from ._wheel.equilibrium import WheelState as WheelState
from ._wheel.equilibrium import solve_wheel as solve_wheel
from ._wheel.passes import PassResult as PassResult
from ._wheel.passes import PathResult as PathResult
from ._wheel.passes import drive_path as drive_path
from ._wheel.passes import Ruts as Ruts
from ._wheel.passes import track_offset as track_offset
from ._wheel.passes import multi_pass as multi_pass

# --- tire (chapter 3) ---
from ._tire.tire import TireCoefficients as TireCoefficients
from ._tire.tire import TireParameters as TireParameters
from ._tire.tire import TireForces as TireForces
from ._tire.sensitivity import TireSensitivities as TireSensitivities
from ._tire.sensitivity import ShearForceVariationRatios as ShearForceVariationRatios
from ._tire.tire import tire_forces as tire_forces
from ._tire.tire import tire_forces_from_parameters as tire_forces_from_parameters
from ._tire.tire import tire_parameters as tire_parameters
from ._tire.sensitivity import tire_force_sensitivities as tire_force_sensitivities
from ._tire.sensitivity import shear_force_variation_ratios as shear_force_variation_ratios
from ._tire.tire import longitudinal_stiffness as longitudinal_stiffness
from ._tire.tire import lateral_stiffness as lateral_stiffness
from ._tire.tire import longitudinal_friction as longitudinal_friction
from ._tire.tire import lateral_friction as lateral_friction
from ._tire.tire import contact_pressure_constant as contact_pressure_constant
from ._tire.slip import shear_distribution as shear_distribution
from ._tire.slip import normalized_longitudinal_slip as normalized_longitudinal_slip
from ._tire.slip import normalized_lateral_slip as normalized_lateral_slip
from ._tire.slip import normalized_combined_slip as normalized_combined_slip
from ._tire.tire import pure_longitudinal_force as pure_longitudinal_force
from ._tire.tire import pure_lateral_force as pure_lateral_force
from ._tire.slip import longitudinal_slip as longitudinal_slip
from ._tire.slip import driving_slip as driving_slip
from ._tire.slip import braking_slip as braking_slip
from ._tire.slip import longitudinal_from_driving_slip as longitudinal_from_driving_slip
from ._tire.slip import driving_from_longitudinal_slip as driving_from_longitudinal_slip
from ._tire.slip import longitudinal_from_braking_slip as longitudinal_from_braking_slip
from ._tire.slip import braking_from_longitudinal_slip as braking_from_longitudinal_slip

# --- tire on snow (chapters 3 + 4) ---
from ._coupled.tire_on_snow import TireOnSnowForces as TireOnSnowForces
from ._coupled.tire_on_snow import tire_forces_on_snow as tire_forces_on_snow

# --- empirical (chapter 2) ---
from ._empirical.models import bekker_compaction_resistance as bekker_compaction_resistance
from ._empirical.models import bekker_rolling_resistance as bekker_rolling_resistance
from ._empirical.models import bekker_wheel_sinkage as bekker_wheel_sinkage
from ._empirical.traction import brixius as brixius
from ._empirical.traction import brixius_wheel_numeric as brixius_wheel_numeric
from ._empirical.traction import BrixiusTraction as BrixiusTraction
from ._empirical.comparison import BrixiusTyre as BrixiusTyre
from ._empirical.comparison import SnowCover as SnowCover
from ._empirical.comparison import compare_motion_resistance as compare_motion_resistance
from ._empirical.traction import gawwad_crolla_slip_parameters as gawwad_crolla_slip_parameters
from ._empirical.traction import gross_traction_coefficient as gross_traction_coefficient
from ._empirical.traction import net_traction_coefficient as net_traction_coefficient
from ._empirical.models import richmond_resistance as richmond_resistance
from ._empirical.traction import rolling_resistance_coefficient as rolling_resistance_coefficient
from ._empirical.models import van_es_compaction_resistance as van_es_compaction_resistance
from ._empirical.models import van_es_rolling_resistance as van_es_rolling_resistance

# --- calibration ---
from ._fit.core import FitResult as FitResult
from ._fit.wheel import fit_parameter_names as fit_parameter_names
from ._fit.plate import fit_plate_sinkage as fit_plate_sinkage
from ._fit.tire import fit_tire_coefficients as fit_tire_coefficients
from ._fit.wheel import fit_wheel as fit_wheel
from ._fit.plate import thesis_plate_test as thesis_plate_test
from ._fit.tire import thesis_tire_table as thesis_tire_table

# --- vehicle simulation ---
from ._sim.planar import PlanarTrajectory as PlanarTrajectory
from ._sim.planar import PlanarVehicle as PlanarVehicle
from ._sim.planar import SteeringProfile as SteeringProfile
from ._sim.planar import planar_wheel_kinematics as planar_wheel_kinematics
from ._sim.planar_stepping import simulate_planar as simulate_planar
from ._sim.stepping import simulate_longitudinal as simulate_longitudinal
from ._sim.options import InitialState as InitialState
from ._sim.options import Stepping as Stepping
from ._sim.vehicle import TorqueProfile as TorqueProfile
from ._sim.vehicle import Trajectory as Trajectory
from ._sim.vehicle import Vehicle as Vehicle
from ._sim.vehicle import WheelForces as WheelForces
from ._sim.vehicle import wheel_forces as wheel_forces
from ._sim.vehicle import wheel_kinematics as wheel_kinematics

# --- sweeps ---
from ._sweep.sweep import SweepResult as SweepResult
from ._sweep.sweep import SweepRun as SweepRun
from ._sweep.storage import iter_sweep_chunks as iter_sweep_chunks
from ._sweep.storage import load_sweep as load_sweep
from ._sweep.sweep import sweep as sweep

# --- reproduction of the thesis; closed-form derivatives of chapter 4 ---
from ._reproduce.registry import reproduce as reproduce
from ._wheel.derivatives import DimensionlessConstants as DimensionlessConstants
from ._wheel.derivatives import ShearDerivatives as ShearDerivatives
from ._wheel.derivatives import shear_derivatives as shear_derivatives
from ._wheel.derivatives import classic_normalized_shear as classic_normalized_shear
from ._wheel.derivatives import simplified_normalized_shear as simplified_normalized_shear
from ._wheel.derivatives import max_normalized_pressure as max_normalized_pressure
from ._wheel.derivatives import contact_angle_at_pressure as contact_angle_at_pressure
from ._wheel.derivatives import thesis_table_4_3 as thesis_table_4_3
from ._wheel.derivatives import thesis_table_4_4 as thesis_table_4_4
from ._wheel.derivatives import thesis_table_4_5 as thesis_table_4_5
from ._wheel.derivatives import thesis_table_4_6 as thesis_table_4_6
from ._wheel.derivatives import thesis_appendix_dz_dsigma as thesis_appendix_dz_dsigma

# --- CRREL shallow-snow model and validation against measured data ---
from ._empirical.crrel import CRREL_FINAL_DENSITIES as CRREL_FINAL_DENSITIES
from ._empirical.crrel import CRRELWheel as CRRELWheel
from ._empirical.crrel import crrel_contact_arc as crrel_contact_arc
from ._empirical.crrel import crrel_drawbar as crrel_drawbar
from ._empirical.crrel import crrel_final_density as crrel_final_density
from ._empirical.crrel import crrel_sinkage as crrel_sinkage
from ._empirical.crrel import crrel_wheel as crrel_wheel
from ._validate.models import ParameterBound as ParameterBound
from ._validate.validate import ValidationModel as ValidationModel
from ._validate.validate import ValidationResult as ValidationResult
from ._validate.validate import crrel_95_1_examples as crrel_95_1_examples
from ._validate.validate import shoop_2001_table11 as shoop_2001_table11
from ._validate.validate import validate as validate
from ._validate.validate import validation_models as validation_models
from ._validate.validate import wheel_validation_model as wheel_validation_model

from ._constants import VERSION

__version__ = VERSION
