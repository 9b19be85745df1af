"""fc_blend.c: estimate/ground-truth blending without steps (paper 3.7, 2.4)."""

import numpy as np
import pytest

import fc_blocks as B

DT = 0.001


def test_weight_follows_a_first_order_ema():
    w = B.Blend(tau_s=0.25).run(np.ones(2000), DT)
    assert w[249] == pytest.approx(1 - np.exp(-1), abs=2e-3)
    assert w[-1] == pytest.approx(1.0, abs=1e-3)


def test_switching_source_makes_no_step_in_the_blended_error():
    target = np.concatenate([np.zeros(500), np.ones(1500), np.zeros(1500)])
    w = B.Blend(tau_s=0.25).run(target, DT)
    e_est, e_gt = 0.10, -0.05                      # the two sources disagree by 0.15 rad
    e = (1 - w) * e_est + w * e_gt
    assert np.abs(np.diff(e)).max() < 0.15 * DT / 0.25 * 1.01
    # the discrete switch (ablation) jumps the whole difference at once
    w_d = B.Blend(tau_s=0.25, continuous=False).run(target, DT)
    e_d = (1 - w_d) * e_est + w_d * e_gt
    assert np.abs(np.diff(e_d)).max() == pytest.approx(0.15)
