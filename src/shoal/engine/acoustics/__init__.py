"""Acoustic source localisation (Chapters 6–8): signals, propagation, the two-hydrophone receiver
and the best-location strategies.
"""
