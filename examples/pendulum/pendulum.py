"""A simple pendulum through every engine, in a few lines and no parameter file: ``python examples/pendulum/pendulum.py``."""
import sys

import study

d = study.Description("pendulum", ["th"], {"m": 1.0, "l": 0.5, "g": 9.81})   # a uniform bar pinned at one end
d.ground("O", 0, 0)
d.body("bar", d.p.m, d.p.m * d.p.l ** 2 / 12, {"O": (-d.p.l / 2, 0)}, angle=d.q[0])
d.revolute("O", (study.GROUND, "O"), ("bar", "O"))
d.gravity(d.p.g)
pendulum = study.Mechanism(d, q0={"th": 1.0}, qd0={"th": 0.0})

if __name__ == "__main__":
    study.validate(pendulum, study.ValidationSettings(t_end=1.0), sys.argv[1] if len(sys.argv) > 1 else "pendulum_out")
