"""State and fault estimation kernels (filters, observers, predictors)."""
