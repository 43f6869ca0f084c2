"""Device drivers as the runtime sees them: each reads its channels into the tick's frame and
writes its outputs from it. Registered by the ``pmactl.drivers`` entry point group."""
