"""The scene kinds, one engine each (core.contract.Engine): the Chapter 3 swarm, the fleet, the
acoustic swarm and the SLO swarm.
"""
