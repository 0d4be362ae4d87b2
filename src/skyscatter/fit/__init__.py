"""Estimating atmosphere parameters from measurements, with uncertainties (`skyscatter fit`).

    measurements.py   the measurement file: radiance, transmittance and chromaticity rows
    parameters.py     the free parameters: config values by dotted key, bounds, start
    forward.py        the forward model of a solver
    sweep_model.py    the forward model of a sweep (interpolation in a precomputed dataset)
    model_error.py    how far each forward model is from the exact answer
    least_squares.py  bounded weighted least squares, covariance, what is not constrained
    retrieval.py      the stages: fit, refine with the tables, check with an exact solver

docs/fit.md describes the method, the file format and the measured accuracy.
"""
