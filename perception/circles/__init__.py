"""Circular objects from 2-D laser scans (seed 001): the polar circle model, circle fits, the
circle EKF, scan segmentation and classification."""
