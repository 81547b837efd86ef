"""The Bayesian engine: particle sets, resampling (SEIR too), dynamics, a Kalman filter, RLS AR(p) predictors and
the fuzzy gain controller (no image code)."""

from .dynamics import ConstantVelocityScale, NCVRandomWalk
from .kalman import KalmanFilter
from .particles import ParticleSet, effective_sample_size, log_normalize, weights_from_log
from .resampling import RESAMPLERS, get_resampler, multinomial, residual, stratified, systematic
from .seir import SEIRInfo, seir

__all__ = [
    "ConstantVelocityScale", "NCVRandomWalk", "KalmanFilter", "ParticleSet", "effective_sample_size",
    "log_normalize", "weights_from_log", "RESAMPLERS", "get_resampler", "multinomial", "residual",
    "stratified", "systematic", "SEIRInfo", "seir",
]
