"""The engine's base: the contract every scene kind implements, the variant registries, seeding,
objectives and the run records.
"""
