"""The waypoint graph: its type and file format, the lattice builder, nearest lookup and paths."""
