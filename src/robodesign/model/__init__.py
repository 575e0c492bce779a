"""The robot model: an assembly built into pinocchio + coal (``Robot``), the robot in a task's cell, and the
certified collision sweeps between samples."""
