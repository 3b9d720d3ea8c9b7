"""Input and output: video frames, MOTChallenge text files, atomic writes."""
