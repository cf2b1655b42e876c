"""docs/trace.md names the columns of vehicle-sim --trace and of vehiclectl
record (over the stream, and polled), in order, and vehicle-sim --help
points there."""
import os
import re
import subprocess
import tempfile
import unittest

from simrig import BUILD, TOP


def documented(section):
    """The column names of the table under a '## ' heading that starts with
    section: backquoted names, 'a' .. 'b' ranges of numbered ones expanded."""
    with open(os.path.join(TOP, "docs/trace.md")) as f:
        text = f.read()
    part = text.split("\n## " + section, 1)[1].split("\n## ", 1)[0]
    names = []
    for line in part.splitlines():
        if not line.startswith("| `"):
            continue
        cell = line.split("|")[1]
        m = re.fullmatch(r" `(\w*?)(\d)(\w*)` \.\. `\w*?(\d)\w*` ", cell)
        if m:
            names += ["%s%d%s" % (m[1], i, m[3]) for i in range(int(m[2]), int(m[4]) + 1)]
        else:
            names += re.findall(r"`(\w+)`", cell)
    return names


class TraceDoc(unittest.TestCase):
    def test_columns_are_documented_in_order(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "t.csv")
            subprocess.run([os.path.join(BUILD, "vehicle-sim"), "--fast", "--trace", path],
                           input=b"$wait 2\n", check=True, capture_output=True, timeout=60)
            with open(path) as f:
                header = f.readline().rstrip("\n").split(",")
        self.assertEqual(documented("`vehicle-sim --trace"), header)
        self.assertEqual(header[-8:], ["state", "queue_len", "alarms", "newest_alarm",
                                       "enc0", "enc1", "enc2", "enc3"])

    def test_record_columns_are_documented_in_order(self):
        with open(os.path.join(TOP, "tools/vehiclectl_main.c")) as f:
            src = f.read()
        # each header: fprintf(csv, "t_s,..." "..." "...\n"), adjacent literals joined
        heads = [re.sub(r'"\s*"', "", m[1]).split(",") for m in
                 re.finditer(r'fprintf\(csv, "(t_s,(?:[^"]|"\s*")*)\\n"\);', src)]
        self.assertEqual(len(heads), 2)
        stream_cols = [h for h in heads if "tick" in h][0]
        poll_cols = [h for h in heads if "tick" not in h][0]
        # the stream's table first (binary frames), then the polled one
        self.assertEqual(documented("`vehiclectl record"), stream_cols + poll_cols)

    def test_help_points_to_the_page(self):
        out = subprocess.run([os.path.join(BUILD, "vehicle-sim"), "--help"], check=True,
                             capture_output=True, text=True, timeout=60).stdout
        self.assertIn("  --trace FILE    CSV trace, one row per tick (columns: docs/trace.md)\n",
                      out)


if __name__ == "__main__":
    unittest.main()
