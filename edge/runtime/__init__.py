"""Runtime pieces of the edge controller."""
