"""Runs on the host: the training loop, experiments of several approaches, checkpoints, run files, comparison
tables, evaluation of trained runs and generalisation sweeps."""
