"""Host-side Python tools for the odometry firmware (plots, reports, log helpers)."""

from .resources import export_for_gap as _export_for_gap

# An installed package (a wheel, not a checkout) tells the gap modules where its data and the
# installed libodosim are; see resources.py. In a checkout this does nothing.
_export_for_gap()
