"""MCAP storage files: the streaming reader, its index plan and time window, the followed tail."""
