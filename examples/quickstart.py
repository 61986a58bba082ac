"""Design a 150 mm circle, cut it from 3 mm acrylic, print it and deploy it: python examples/quickstart.py [FOLDER]"""

import sys
import tempfile
from pathlib import Path

import fabkiri

out = Path(sys.argv[1]) if sys.argv[1:] else Path(tempfile.mkdtemp(prefix="fabkiri-"))
design = fabkiri.design("circle", tiles="8x8", size=150, rigid=True)  # the target, its tiles, mm
cut = fabkiri.cut(design.pattern, material="acrylic-3", scale="auto")  # DXF, SVG, PNG, manifest
printed = fabkiri.print_pattern(design.pattern, printer="prusa-mk4", scale="auto")  # 3MF, STL
deployed = fabkiri.deploy(design.pattern, frames=False)  # the path between the closed states
for name, result in [("design", design), ("cut", cut), ("print", printed), ("deploy", deployed)]:
    result.write(out / name)  # in a notebook, display(result) shows its picture
    print(result.summary())
sys.exit(0 if all(r.ok for r in (design, cut, printed, deployed)) else 1)
