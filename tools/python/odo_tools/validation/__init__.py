"""Validation of the gap diagnosis on worlds it did not generate (the blind check)."""
