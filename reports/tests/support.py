"""What the report builder's tests share: the report modules on the path, and a real physbench run."""
from __future__ import annotations

import base64
import gzip
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PHYSBENCH = os.environ.get("PHYSBENCH_EXE")


def physbench_run(out: Path, *args: str) -> Path:
    """`physbench run ARGS --budget 0 --out OUT`, checked; the test is skipped without the executable."""
    if not PHYSBENCH:
        pytest.skip("PHYSBENCH_EXE is not set (CTest sets it)")
    subprocess.run([PHYSBENCH, "run", *args, "--budget", "0", "--out", str(out)], check=True, capture_output=True)
    return out


def figure_specs(html: str) -> list[dict]:
    """The plotly figures (dict(data, layout)) a page fragment carries, decoded as the page's
    script decodes them: each chart's JSON, gzipped and in base64 beside its div."""
    return [json.loads(gzip.decompress(base64.b64decode(text)))
            for text in re.findall(r'<script type="text/plain" class="chart-spec" data-for="[^"]+">([^<]*)</script>', html)]


def readable(page: str) -> str:
    """The page with each chart's gzipped JSON written out as the JSON text plotly wrote (where "/"
    is "\\u002f"), in place, for tests that look for what a chart says."""
    return re.sub(r'<script type="text/plain" (class="chart-spec" data-for="[^"]+">)([^<]*)(</script>)',
                  lambda m: '<script type="application/json" ' + m.group(1)
                  + gzip.decompress(base64.b64decode(m.group(2))).decode() + m.group(3), page)
