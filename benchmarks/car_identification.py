"""Section IV's experiment on a passenger car (studies/passenger_car_identification.toml, issue
26): how close the identified RLF model comes to the RLF transfer function of the car's own
numbers at 20 m/s, over the excited band (0.02-2 Hz).

    python3 benchmarks/car_identification.py
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from agrobot.components.models.yaw_dynamics import TractorParameters, transfer_function
from agrobot.identification.pipeline import identify_study
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parent.parent
CAR = TractorParameters(m=1500.0, I=2500.0, l_f=1.2, l_r=1.5, C_f=80000.0, C_r=100000.0, sigma_f=0.5, sigma_r=1.0)


def main() -> None:
    report = identify_study(Study.load(ROOT / "studies" / "passenger_car_identification.toml"), None, plots=False)
    num, den = transfer_function("rlf", CAR, 20.0)
    fit = report["models"]["rlf"]
    w = 2 * np.pi * np.linspace(0.02, 2.0, 200)
    true = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    got = np.polyval(fit["num"], 1j * w) / np.polyval(fit["den"], 1j * w)
    dc = (fit["num"][-1] / fit["den"][-1]) / (num[-1] / den[-1]) - 1.0
    print(f"identified RLF vs the car's RLF at 20 m/s: DC gain {100 * dc:+.1f} %, "
          f"largest frequency-response error over 0.02-2 Hz {100 * np.max(np.abs(got - true) / np.abs(true)):.1f} %")


if __name__ == "__main__":
    main()
