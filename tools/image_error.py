#!/usr/bin/env python3
"""Where the image error of two frames sits: by bands of rows, and by scale.

Usage: tools/image_error.py REFERENCE.png TEST.png [BANDS]

Prints mean FLIP (NVIDIA's LDR-FLIP through the `flip-evaluator` package) over the
whole frame, then per band of rows (FLIP, mean luma of each image, share of the total
error), over sky and non-sky pixels, and at 2x, 4x and 8x box-averaged resolution (the
frames seen from twice, four and eight times as far, or on a display that many times
smaller). Needs `pip install flip-evaluator pillow numpy`.
"""
import sys

import flip_evaluator
import numpy as np
from PIL import Image


def load(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.float32) / 255.0


def luma(im):
    # Rec. 709 weights on the stored (display) values: a brightness to compare, not a
    # physical luminance.
    return 0.2126 * im[..., 0] + 0.7152 * im[..., 1] + 0.0722 * im[..., 2]


def box(im, k):
    h, w = im.shape[0] // k * k, im.shape[1] // k * k
    return im[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def flip(ref, test):
    err, mean, _ = flip_evaluator.evaluate(ref, test, "LDR")
    err = err if err.ndim == 2 else err[..., 0]
    return err, float(mean)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    ref, test = load(sys.argv[1]), load(sys.argv[2])
    if ref.shape != test.shape:
        sys.exit(f"the frames differ in size: {ref.shape[:2]} and {test.shape[:2]}")
    bands = int(sys.argv[3]) if len(sys.argv) > 3 else 8
    err, mean = flip(ref, test)
    print(f"mean FLIP {mean:.3f}")
    height = err.shape[0]
    lr, lt = luma(ref), luma(test)
    total = max(err.sum(), 1e-12)
    print("rows       FLIP   luma ref  luma test  share of error")
    for i in range(bands):
        r0, r1 = i * height // bands, (i + 1) * height // bands
        print(
            f"{r0:4d}-{r1:4d}  {err[r0:r1].mean():.3f}   {lr[r0:r1].mean():.3f}     "
            f"{lt[r0:r1].mean():.3f}      {err[r0:r1].sum() / total:.2f}"
        )
    # Sky: blue clearly above green in the reference.
    sky = (ref[..., 2] > ref[..., 1] + 0.05) & (ref[..., 2] > 0.5)
    if sky.any() and (~sky).any():
        print(
            f"sky {sky.mean():.2f} of the frame: FLIP {err[sky].mean():.3f}; "
            f"elsewhere FLIP {err[~sky].mean():.3f}, "
            f"luma {lr[~sky].mean():.3f} -> {lt[~sky].mean():.3f}"
        )
    for k in (2, 4, 8):
        _, m = flip(box(ref, k), box(test, k))
        print(f"{k}x box-averaged: FLIP {m:.3f}")


if __name__ == "__main__":
    main()
