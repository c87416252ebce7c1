"""Particle swarm optimisation: Chapter 3 velocity laws, coefficient policies and tuning, stability
regions, SPSO 2011 and the bests.
"""
