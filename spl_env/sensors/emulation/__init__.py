"""sensors/emulation"""
