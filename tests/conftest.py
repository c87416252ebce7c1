"""Test-wide settings: hypothesis checks behaviour, not speed, on a shared 2-core machine."""

from hypothesis import settings

settings.register_profile("shoal", deadline=None)
settings.load_profile("shoal")
