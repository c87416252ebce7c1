"""Robots with bodies (Chapters 4–5): worlds, six-sector sensing, motion, the fleet's velocity laws
and DVC.
"""
