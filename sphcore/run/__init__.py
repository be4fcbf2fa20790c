"""How a run goes: build, the step loop, relaxation, start-up checks, checkpoints and restart, threads, progress."""
