"""Where the original TU Graz system's real files are: ``../shared/data/tug-original``.

The sample of real model files and the repair domain of paper 000's system lives beside the
checkout, or beside a folder above it (GPLv3 upstream: used from there, never copied into the
project). ``DXBOARD_SHARED`` names another ``shared`` directory.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: ``shared`` beside the checkout, or beside a folder above it (a worktree in /work/wt/NAME)
SHARED = Path(os.environ.get("DXBOARD_SHARED") or next(
    (p / "shared" for p in ROOT.parents if (p / "shared" / "data").is_dir()),
    ROOT.parent / "shared"))
ORIGINAL = SHARED / "data" / "tug-original"
ISCAS = SHARED / "data" / "iscas85"

#: the sample's files by what they exercise (see its README)
PIONEER = ORIGINAL / "tug_ist_diagnosis_model_diagnosis_model_pioneer_f5db7bb_809fc814.yaml"
FINAL = ORIGINAL / "tug_ist_diagnosis_model_diagnosis_modelFinal_09ec582_089c399b.yaml"
MODEL2 = ORIGINAL / "tug_ist_diagnosis_model_diagnosis_model2_dc7c835_9367187c.yaml"
JAGUAR_2012 = ORIGINAL / "zinni_2012-06-11_66466cc_diagnosis_model_diagnosis_model_bb552a5b.yaml"
PROTOTYPE = ORIGINAL / "zinni_2012-01-05_7719145_diagnosis_observers_SD_daa2f131.yaml"
BROKEN_YAML = ORIGINAL / "tug_ist_diagnosis_model_diagnosis_modelFinalRound_7e25a4e_099276c7.yaml"
DOMAIN = ORIGINAL / "tug_ist_diagnosis_repair_repair_domain_fcfc67d.pddl"
PROBLEM = ORIGINAL / "tug_ist_diagnosis_repair_java_classes_repair_problem_6bdfab2.pddl"
