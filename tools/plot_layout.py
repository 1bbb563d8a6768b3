"""The stacked time plots of tools/plot_trajectory.py and tools/plot_physx_diff.py (each run as a
script, so this module is found beside them)."""
from matplotlib.figure import Figure  # not pyplot: savefig picks Agg for a PNG itself


def stacked_axes(n, title):
    """n axes sharing t, one above the other, on a 10 x 10 inch figure laid out in inches for
    10 pt text: tight_layout would measure every label first, as costly as drawing them."""
    width, height = 10.0, 10.0
    left, right, top, bottom, gap = 1.0, 0.15, 0.5, 0.6, 0.3  # gap: room for a "1e-5" offset
    axes_height = (height - top - bottom - (n - 1) * gap) / n
    fig = Figure(figsize=(width, height))
    axes = fig.subplots(n, 1, sharex=True, squeeze=False, gridspec_kw=dict(
        left=left / width, right=1 - right / width, top=1 - top / height, bottom=bottom / height,
        hspace=gap / axes_height))[:, 0]
    fig.suptitle(title, y=1 - 0.1 / height, va="top")
    return fig, axes
