"""Remote inputs in S3, GCS or on HTTP servers: the stores, stall-watched fetches, range reads."""
