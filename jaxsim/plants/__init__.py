"""Plants of the seed papers, one module per family (``Params`` + ``dynamics`` + ``output``)."""
