"""Runs that robotics tools open: ``run.mcap`` (Foxglove schemas) and a live Foxglove WebSocket view."""
