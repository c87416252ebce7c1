"""Thesis reproductions and parameter sweeps: the only engine code that reads presets."""
