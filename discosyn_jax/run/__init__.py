"""The run folder: every name in it (layout), its one owner and writer, finding and reading
a run, crash-safe checkpoints, atomic files, logs; stops (Ctrl-C, SIGTERM) and the compile
cache a process keeps."""
