"""The moving belt's stream, measured: which starts can be saved, what supply the cell sustains.

`starts`: the stream's starts no order of picks saves; `stress`: the highest supply rate the
scripted cell keeps up with.
"""
