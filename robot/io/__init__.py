"""Results: the Result type, file format and atomic writes."""
