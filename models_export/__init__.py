"""Export of identified models into bundles the edge loads (lookup tables today)."""
