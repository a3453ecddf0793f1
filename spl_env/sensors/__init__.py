"""Sensor models turning the simulated world's ground truth into what the robot measures."""
