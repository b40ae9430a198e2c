#!/usr/bin/env bash
# bench/psnr.sh A.png B.png — the PSNR of two pictures in dB (`inf` if identical): ImageMagick's, or where it is
# not installed (a GPU machine), the same figure from Python's Pillow (NumPy if there): 10·log10(1/MSE) over
# the RGB channels scaled to [0, 1] (iqc render's PNGs have no alpha); `?` without either.
if [ -x /usr/bin/compare ]; then /usr/bin/compare -metric PSNR "$1" "$2" null: 2>&1 || true; exit 0; fi
python3 - "$1" "$2" 2>/dev/null <<'PY' || echo "?"
import sys, math
from PIL import Image
a, b = (Image.open(f).convert("RGB").tobytes() for f in sys.argv[1:3])
try:
    import numpy as np
    d = np.frombuffer(a, np.uint8).astype(np.float64) - np.frombuffer(b, np.uint8)
    sse = float(np.dot(d, d))
except ImportError:
    sse = float(sum((x - y) ** 2 for x, y in zip(a, b)))
mse = sse / (255.0 ** 2 * len(a))
print("inf" if mse == 0 else f"{10 * math.log10(1 / mse):.4g}")
PY
