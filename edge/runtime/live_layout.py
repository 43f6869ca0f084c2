"""The Foxglove layout shipped as ``docs/examples/foxglove-layout.json``: tracking (reference
and contraction), the valve's command parts against the measured pressure, the forward twin
(its prediction, residual and the adapted offset and gain; single muscle), lateness, and the
event log, on the topics of the live view and the MCAP export (:mod:`edge.runtime.live`).

Regenerate the file with ``python -m edge.runtime.live_layout > docs/examples/foxglove-layout.json``
(a test checks they agree). In Foxglove: Layouts -> Import from file.
"""

from __future__ import annotations

from edge.runtime.mcap_export import EVENT_TOPIC, TICK_TOPIC


def layout_json(output: str = "contraction_mm", reference: str = "reference_mm") -> str:
    """The layout as JSON (a joint: ``angle_deg``, ``reference_deg``)."""
    import foxglove.layouts as fl

    def plot(title: str, *fields: str) -> fl.PlotPanel:
        series = [fl.PlotSeries(value=f"{TICK_TOPIC}.{f}", label=f) for f in fields]
        return fl.PlotPanel(title=title, config=fl.PlotConfig(paths=series))

    tracking = plot("tracking", reference, output)
    valve = plot("valve command and pressure", "u_bar", "u_ff_bar", "u_fb_bar", "pressure_bar")
    timing = plot("tick lateness [us] and state", "lateness_us", "state", "fault")
    twin_fields = ("twin_mm", "twin_residual_mm", "adapt_offset_mm", "adapt_gain")
    twin = plot("forward twin [mm] and adaptation", output, *twin_fields)
    events = fl.RawMessagesPanel(title="events", config=fl.RawMessagesConfig(topic_path=EVENT_TOPIC))
    column = fl.SplitContainer(
        direction="column",
        items=[
            fl.SplitItem(proportion=2, content=tracking),
            fl.SplitItem(content=valve),
            *([fl.SplitItem(content=twin)] if output == "contraction_mm" else []),  # a joint has no twin
            fl.SplitItem(content=timing),
        ],
    )
    content = fl.SplitContainer(
        direction="row", items=[fl.SplitItem(proportion=3, content=column), fl.SplitItem(content=events)]
    )
    return fl.Layout(content=content).to_json()


if __name__ == "__main__":
    print(layout_json())
