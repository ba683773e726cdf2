"""The firmware on its Cortex-M4: instruction counts in an emulator, flash/RAM/stack figures."""
