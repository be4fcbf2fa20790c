"""Output: the output directory and its marker, writers' shared behaviour and schedules."""
