"""Checks of the project's tools against worlds and data they did not generate (the blind check)."""


def case_seed(seed: int, k: int) -> int:
    """The data seed of case k of a blind draw with seed `seed` (its noise, floor and timing).
    odo-gap blind, the gap bench, the independent world's bench and its by-hand CLI
    (`python -m odo_tools.validation.indep --seed S --case K`) all take it from here, so a case
    written by hand is the very case a blind run diagnosed."""
    return seed * 1000 + k
