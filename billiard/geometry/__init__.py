"""The container: boundary curves, their walls, the drive, and the offset surfaces a ball
centre stays on.
"""
