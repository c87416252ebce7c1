"""Simultaneous Localisation and Optimisation (Mai): sensors, candidates, selections, beliefs,
neighbourhoods and positions.
"""
