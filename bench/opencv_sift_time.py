#!/usr/bin/python3
"""OpenCV's SIFT on one photo, one thread: median milliseconds of decode + detectAndCompute.

Usage: bench/opencv_sift_time.py PHOTO RUNS [CONTRAST]
Prints "MS FEATURES". Needs Debian's python3-opencv (/usr/bin/python3). OpenCV's defaults: 3
layers per octave, contrast threshold 0.04, edge 10, sigma 1.6, the image doubled first. It
keeps a refined extremum when |DoG| >= contrast / 3 of the intensity range, so COLMAP's peak
threshold (0.02 / 3) is CONTRAST 0.02; COLMAP's edge threshold is OpenCV's 10 already.
"""
import statistics
import sys
import time

import cv2


def main():
    photo, runs = sys.argv[1], int(sys.argv[2])
    contrast = float(sys.argv[3]) if len(sys.argv) > 3 else 0.04
    cv2.setNumThreads(1)
    sift = cv2.SIFT_create(contrastThreshold=contrast)
    times, count = [], 0
    for _ in range(runs + 1):  # the first run warms up
        start = time.perf_counter()
        grey = cv2.imread(photo, cv2.IMREAD_GRAYSCALE)
        keypoints, _ = sift.detectAndCompute(grey, None)
        times.append((time.perf_counter() - start) * 1000)
        count = len(keypoints)
    print(f"{statistics.median(times[1:]):.0f} {count}")


if __name__ == "__main__":
    main()
