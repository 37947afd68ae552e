"""Small utilities every floor may use: atomic file writes, the smooth reward, CLI plumbing, the compile cache."""
