#!/usr/bin/python3
"""Tests of tools/compare_runs.py (ctest unit/tools/CompareRuns).

Usage: test_compare_runs.py [workdir]

Synthetic compaction CSVs with known answers: eps(Phi) = -(Phi - 0.8) and sigma/M_p(Phi) =
-(Phi - 0.8)^2, sampled on rows that do not fall on the targets.
- eps is interpolated at the targets and sigma averaged over the windows (values checked);
- a run with eps shifted by 0.003 and sigma scaled by 1.01 passes the default bounds, one with
  eps shifted by 0.006 or sigma scaled by 1.03 does not (exit 1), and the reported differences
  are those put in;
- a noise run is printed as such and does not count in the verdict; with two, the floor is the
  larger of their differences and runs are judged against it as well;
- the ledger is given in per cent of the walls' work;
- bad input (a missing file, a CSV without the columns, a run short of the last target, bad
  --targets) gives exit 2 and a message naming the file or option.
"""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "..", "tools")
sys.path.insert(0, TOOLS)
import compare_runs as cr  # noqa: E402

WORK = sys.argv.pop(1) if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="compare_runs_")
SCRIPT = os.path.join(TOOLS, "compare_runs.py")


def write(name, d_eps=0.0, s_scale=1.0, top=0.975, columns=None):
    """A synthetic run CSV; returns its path."""
    path = os.path.join(WORK, name)
    head = columns or ["step", "phi", "eps", "sigma_bottom_over_Mp", "wall_top_work",
                       "wall_bottom_work", "energy_change", "contact_dissipation",
                       "transfer_dissipation", "internal_dissipation"]
    with open(path, "w") as f:
        f.write(",".join(head) + "\n")
        phi, k = 0.8003, 0
        while phi <= top:
            vals = {"step": k, "phi": phi, "eps": -(phi - 0.8) + d_eps,
                    "sigma_bottom_over_Mp": -s_scale * (phi - 0.8) ** 2, "wall_top_work": 3.0,
                    "wall_bottom_work": 1.0, "energy_change": 3.0, "contact_dissipation": 0.5,
                    "transfer_dissipation": 0.3, "internal_dissipation": 0.2}
            f.write(",".join(repr(vals[c]) for c in head) + "\n")
            phi += 0.0007
            k += 1
    return path


def run(*args):
    p = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


class CompareRuns(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        os.makedirs(WORK, exist_ok=True)
        cls.ref = write("ref.csv")

    def test_interpolation_and_windows(self):
        r = cr.load(self.ref)
        self.assertAlmostEqual(cr.eps_at(r, 0.9), -0.1, places=12)  # linear: exact
        # mean of -(phi - 0.8)^2 over the rows in [0.88, 0.90]: close to the integral mean
        m = cr.sigma_mean(r, 0.88, 0.90)
        exact = -((0.1 ** 3 - 0.08 ** 3) / 3) / 0.02
        self.assertAlmostEqual(m, exact, delta=2e-5)
        self.assertTrue(cr.eps_at(r, 0.99) != cr.eps_at(r, 0.99))  # never reached: nan
        self.assertEqual([round(x, 9) for x in cr.ledger(r, 0.97)], [75.0, 12.5, 7.5, 5.0])

    def test_differences_and_verdicts(self):
        ok = write("ok.csv", d_eps=0.003, s_scale=1.01)
        rc, out, _ = run(self.ref, ok)
        self.assertEqual(rc, 0, out)
        self.assertIn("+0.0030", out)
        self.assertIn("+1.0%", out)
        self.assertIn("max |d eps| 0.0030", out)
        self.assertIn("within 0.005 in eps (ok) and 2 % in sigma (ok)", out)
        bad_e = write("bad_eps.csv", d_eps=0.006)
        bad_s = write("bad_sigma.csv", s_scale=1.03)
        rc, out, _ = run(self.ref, ok, bad_e, bad_s)
        self.assertEqual(rc, 1, out)
        self.assertIn("NOT within 0.005 in eps (no) and 2 % in sigma (ok)", out)
        self.assertIn("NOT within 0.005 in eps (ok) and 2 % in sigma (no)", out)
        rc, out, _ = run(self.ref, bad_s, "--sigma-tol", "0.04")
        self.assertEqual(rc, 0, out)

    def test_noise_is_shown_not_judged(self):
        noisy = write("noise.csv", s_scale=1.05)
        ok = write("ok2.csv", d_eps=-0.001)
        rc, out, _ = run(self.ref, ok, "--noise", noisy)
        self.assertEqual(rc, 0, out)
        self.assertIn("(rearrangements alone)", out)
        self.assertIn("+5.0%", out)
        # two noise runs: the floor is the larger; a 3 % run is within it but not within 2 %
        noisy2 = write("noise2.csv", d_eps=0.002, s_scale=0.98)
        inside = write("inside.csv", d_eps=-0.0015, s_scale=1.03)
        outside = write("outside.csv", s_scale=1.06)
        rc, out, _ = run(self.ref, inside, outside, "--noise", noisy, "--noise", noisy2)
        self.assertEqual(rc, 1, out)
        self.assertIn("noise floor (largest over the noise runs)", out)
        self.assertIn("max |d eps| 0.0020", out)
        blocks = out.split(os.path.join(WORK, "inside.csv"))[1].split(os.path.join(WORK, "outside.csv"))
        self.assertIn("NOT within 0.005 in eps (ok) and 2 % in sigma (no)", blocks[0])
        self.assertIn("  within the noise floor (eps ok, sigma ok)", blocks[0])
        self.assertIn("NOT within the noise floor (eps ok, sigma no)", blocks[1])

    def test_bad_input_exits_2(self):
        rc, _, err = run(self.ref, os.path.join(WORK, "missing.csv"))
        self.assertEqual(rc, 2)
        self.assertIn("missing.csv: cannot read", err)
        nocol = write("nocol.csv", columns=["step", "phi", "eps"])
        rc, _, err = run(self.ref, nocol)
        self.assertEqual(rc, 2)
        self.assertIn("nocol.csv: no column 'sigma_bottom_over_Mp'", err)
        short = write("short.csv", top=0.95)
        rc, _, err = run(self.ref, short)
        self.assertEqual(rc, 2)
        self.assertIn("below the last target", err)
        rc, _, err = run(self.ref, self.ref, "--targets", "0.9,x")
        self.assertEqual(rc, 2)
        self.assertIn("--targets", err)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]])
