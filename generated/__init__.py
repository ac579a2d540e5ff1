"""Generated numeric code. Never edit by hand: run `billiard derive`."""
