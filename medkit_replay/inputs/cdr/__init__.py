"""CDR payload decoders: generated from definitions, hand-written, their bounds and refusals."""
