"""Input and output: video frames, MOTChallenge text files, atomic writes.

Importing this package keeps OpenCV's and FFmpeg's own log lines off the terminal
(:mod:`mvtrack.io.logs`): mvtrack reports problems with its inputs itself, in one line.
"""

from mvtrack.io.logs import quiet_backends

quiet_backends()
