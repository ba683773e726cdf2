"""Checks of the project's tools against worlds and data they did not generate (the blind check)."""
