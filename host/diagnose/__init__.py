"""``pmactl diagnose``: what the simulation gets wrong on measured data, why, and what fixing it gains.

``features``: the regressors (Preisach hysteresis rows, rate, creep, load, temperature, delay).
``hammerstein``: the baseline (hysteresis + ARX, orders by AIC) and its extensions.
``evidence``: residual diagnostics. ``run``: the held-out comparison and the verdict.
``report``: Markdown + figures.
"""
