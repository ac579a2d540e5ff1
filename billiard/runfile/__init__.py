"""Records and the files of a run: impact records and rows, streamed CSV files, side files,
checkpoints.
"""
