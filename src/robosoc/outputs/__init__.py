"""What a run leaves for people and tools: the run folder (flight log, job records, summary),
the flight's MCAP, the chip trace, the HTML report, the live Foxglove server, and the sessions that
fly a scenario and write them (lockstep and decoupled)."""
