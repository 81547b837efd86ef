"""The Bayesian engine: particle sets, resampling, dynamics and a Kalman filter (no image code)."""

from .dynamics import ConstantVelocityScale, NCVRandomWalk
from .kalman import KalmanFilter
from .particles import ParticleSet, effective_sample_size, log_normalize, weights_from_log
from .resampling import RESAMPLERS, get_resampler, multinomial, residual, stratified, systematic

__all__ = [
    "ConstantVelocityScale", "NCVRandomWalk", "KalmanFilter", "ParticleSet", "effective_sample_size",
    "log_normalize", "weights_from_log", "RESAMPLERS", "get_resampler", "multinomial", "residual",
    "stratified", "systematic",
]
