"""stepgen: a faithful model of LinuxCNC's software step generator, and its timing calculator."""
