"""``pmactl diagnose``: what the simulation gets wrong on measured data, why, and what fixing it gains.

``features``: the regressors (Preisach rows, rate, creep, branch). ``hammerstein``: the baseline
(hysteresis + ARX, orders by AIC; ``fit_gains`` for fixed poles). ``candidates``: the
extensions, one physical term each, identified on the whole record, and the columns' surrogates.
``folds``: held-out blocks and the noise floor.
``decide``: the calibrated verdict and its confidence. ``run``: one record. ``crossrun``: a
model identified on one record checked on others. ``evidence``: residual diagnostics.
``signatures``: surrogate-calibrated residual tests that nominate a cause (hold drift,
reversal lag).
``report``: Markdown + figures.
"""
