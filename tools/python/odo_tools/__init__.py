"""Host-side Python tools for the odometry firmware (plots, reports, log helpers)."""
