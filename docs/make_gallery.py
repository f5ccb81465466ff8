"""Regenerate the gallery's figures in docs/gallery/ (run from the repository root; about a minute).

    .venv/bin/python docs/make_gallery.py

The demo's two figures (``symid demo``) and the Bode plot of the README's own-model example
(``symid identify spring.py --data measured.csv ...``), written in a scratch folder and copied here.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def main() -> int:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = next(b for b in readme.split("```python\n")[1:] if "spring.py" in b).split("```", 1)[0]
    symid = Path(sys.executable).with_name("symid")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = {**os.environ, "MPLBACKEND": "Agg"}
        subprocess.run([str(symid), "demo", "--out", str(work / "demo")], check=False, cwd=work, env=env)
        subprocess.run([sys.executable, "-c", block], check=True, cwd=work, env=env)
        subprocess.run([str(symid), "identify", "spring.py", "--data", "measured.csv", "--columns", "frequency=f_Hz",
                        "magnitude=mag_dB", "phase=phase_deg", "--units", "frequency=Hz", "magnitude=dB",
                        "phase=deg", "--method", "ipopt", "--out", "fit"], check=True, cwd=work, env=env)
        out = HERE / "gallery"
        out.mkdir(exist_ok=True)
        for src, name in ((work / "demo" / "bode.png", "demo_bode.png"),
                          (work / "demo" / "convergence.png", "demo_convergence.png"),
                          (work / "fit" / "bode.png", "own_model_bode.png")):
            shutil.copyfile(src, out / name)
            print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
