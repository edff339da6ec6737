"""The core package passes mypy with the repository's configuration (``[tool.mypy]`` in pyproject.toml:
every module of ``core/infuse``, the public API module and the foot-contact component strictly).
mypy comes with the ``test`` extra; its cache lives in the virtual environment, so a rerun takes
seconds."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_mypy_finds_nothing_in_the_core():
    proc = subprocess.run([sys.executable, "-m", "mypy", "--no-error-summary", "--hide-error-context"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert "No module named mypy" not in proc.stderr, "mypy is missing: pip install -e '.[test]'"
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_public_api_module_is_strictly_typed():
    proc = subprocess.run([sys.executable, "-m", "mypy", "--strict", "--follow-imports=silent", "--no-error-summary",
                           "core/infuse/api.py", "core/infuse/footing.py", "core/infuse/contacts.py",
                           "core/infuse/stage.py"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr


#: Plugin packages and modules that pass mypy: the controllers whose contracts are typed (bindings and
#: per-character and per-activity state as dataclasses), and the readers, speech engines and the nonverbal
#: generator whose findings are fixed (only their own findings: what they import is checked where it lives).
TYPED_PLUGIN_MODULES = ["plugins/gaze/infuse_gaze", "plugins/gestures/infuse_gestures/controller.py",
                        "plugins/postures/infuse_postures", "plugins/lipsync/infuse_lipsync", "plugins/head/infuse_head",
                        "plugins/blink/infuse_blink", "plugins/breathing/infuse_breathing",
                        "plugins/saccade/infuse_saccade", "plugins/noise/infuse_noise",
                        "plugins/manipulation/infuse_manipulation", "plugins/reach/infuse_reach",
                        "plugins/ogre/infuse_ogre", "plugins/acclaim/infuse_acclaim", "plugins/tts_espeak/infuse_tts_espeak",
                        "plugins/tts_file/infuse_tts_file", "plugins/nvbg/infuse_nvbg", "plugins/locomotion/infuse_locomotion"]


def test_the_typed_plugins_pass_mypy():
    proc = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-error-summary",
                           "--hide-error-context", *TYPED_PLUGIN_MODULES],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
