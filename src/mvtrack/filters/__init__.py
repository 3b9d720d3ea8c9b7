"""Predictors: batched linear Kalman filters, the RLS adaptive predictor, the structured KF."""
