"""Reading and plotting what training and sweeps produced: curves, tables, episode logs."""
