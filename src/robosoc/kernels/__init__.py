"""The only numba code in robosoc: the core step and (later) the NoC cycle, arrays in, arrays out."""
