"""What is asked: case.toml read, --set applied, options validated against the defaults, finite walls built."""
