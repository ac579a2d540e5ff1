"""Records and the files of a run: impact records and rows, streamed CSV files and their
binary counterparts (``.npy`` rows), side files, checkpoints.
"""
