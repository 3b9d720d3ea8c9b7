"""Detection front ends: disturbance map, frame differencing, MOG2, template matching, parts."""
