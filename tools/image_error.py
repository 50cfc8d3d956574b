#!/usr/bin/env python3
"""Where the image error of two frames sits: by bands of rows, and by scale.

Usage: tools/image_error.py REFERENCE.png TEST.png [BANDS] [--crop X0,Y0,X1,Y1]

Prints mean FLIP (NVIDIA's LDR-FLIP through the `flip-evaluator` package) over the
whole frame, then per band of rows (FLIP, mean luma of each image, share of the total
error), over sky and non-sky pixels, and at 2x, 4x and 8x box-averaged resolution (the
frames seen from twice, four and eight times as far, or on a display that many times
smaller), and the fine contrast of each: the standard deviation of luma within 4x4
blocks, averaged (lower in the test when it is blurred, higher when it is grainier).
`--crop` compares only the pixels from (X0, Y0) up to (X1, Y1), e.g. a stand of trees
without the ground around it. Needs `pip install flip-evaluator pillow numpy`.
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
    # The error itself, not the magma colour map the package applies by default.
    err, mean, _ = flip_evaluator.evaluate(ref, test, "LDR", applyMagma=False)
    err = err if err.ndim == 2 else err[..., 0]
    return err, float(mean)


def fine_contrast(lum):
    h, w = lum.shape[0] // 4 * 4, lum.shape[1] // 4 * 4
    return float(lum[:h, :w].reshape(h // 4, 4, w // 4, 4).std(axis=(1, 3)).mean())


def crop_box(text, shape):
    try:
        x0, y0, x1, y1 = (int(v) for v in text.split(","))
    except ValueError:
        sys.exit(f"--crop {text!r}: expected four integers X0,Y0,X1,Y1")
    if not (0 <= x0 and x0 + 16 <= x1 <= shape[1] and 0 <= y0 and y0 + 16 <= y1 <= shape[0]):
        sys.exit(f"--crop {text!r}: not a region of at least 16x16 inside the {shape[1]}x{shape[0]} frame")
    return (slice(y0, y1), slice(x0, x1))


def main():
    args = sys.argv[1:]
    crop = None
    if "--crop" in args:
        i = args.index("--crop")
        if i + 1 >= len(args):
            sys.exit("--crop needs X0,Y0,X1,Y1")
        crop = args[i + 1]
        del args[i : i + 2]
    if len(args) < 2:
        sys.exit(__doc__)
    ref, test = load(args[0]), load(args[1])
    if ref.shape != test.shape:
        sys.exit(f"the frames differ in size: {ref.shape[:2]} and {test.shape[:2]}")
    if crop is not None:
        region = crop_box(crop, ref.shape)
        ref, test = ref[region], test[region]
    try:
        bands = int(args[2]) if len(args) > 2 else 8
    except ValueError:
        sys.exit(f"BANDS {args[2]!r}: expected a whole number of row bands")
    if not 1 <= bands <= ref.shape[0]:
        sys.exit(f"BANDS {bands}: between 1 and the frame's {ref.shape[0]} rows")
    err, mean = flip(ref, test)
    print(f"mean FLIP {mean:.4f}")
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
            f"luma {lr[~sky].mean():.3f} -> {lt[~sky].mean():.3f} "
            f"({100 * (lt[~sky].mean() / max(lr[~sky].mean(), 1e-6) - 1):+.1f} %)"
        )
    print(f"fine contrast (luma std in 4x4 blocks): {fine_contrast(lr):.4f} -> {fine_contrast(lt):.4f}")
    for k in (2, 4, 8):
        _, m = flip(box(ref, k), box(test, k))
        print(f"{k}x box-averaged: FLIP {m:.4f}")


if __name__ == "__main__":
    main()
