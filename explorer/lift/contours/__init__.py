"""Cam geometry: exact envelopes (synthesis), follower lift from a contour (analysis), arc cams."""
