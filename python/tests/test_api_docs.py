"""scripts/api_docs.py: the API reference names every public name of the module with its stub's
signature and its docstring's text (the stubs themselves are checked in test_learning.py)."""
import os
import subprocess
import sys

import voxfx

SCRIPT = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "api_docs.py")


def test_the_api_reference_names_every_public_name(tmp_path):
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(voxfx.__file__)))
    subprocess.run([sys.executable, SCRIPT, str(tmp_path)], check=True, capture_output=True, env=env)
    text = (tmp_path / "api.md").read_text()
    for name in voxfx.__all__:
        assert f"\n## {name}\n" in text, name
    # A signature from the stub, text from the docstring.
    assert "sample_near_surface(mesh: MeshLike, n: int, sigma: Union[float, Sequence[float]]" in text
    assert "MinkowskiEngine" in text and (tmp_path / "api.html").exists() and (tmp_path / "voxfx.html").exists()
