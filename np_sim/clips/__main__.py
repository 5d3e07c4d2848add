"""``python -m np_sim.clips``: the clips' command line (`np_sim.clips.cli`)."""

from np_sim.clips.cli import main

main()
