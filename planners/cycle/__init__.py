"""The pick-and-place cycle's parts: the arm's moves and the leads at the approach points."""
