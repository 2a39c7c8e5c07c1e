"""What an rviz screenshot shows, for the screenshot tests (scanstop_sim, scanstop_mesher): an rviz
config turned into a top-down view of known scale (so a world point has a known pixel), rviz run
full screen under xvfb-run, and the screenshot read back with the world -> pixel map."""
import math
import re

import xwd_image


def top_down_config(config_text, scale, focus):
    """The rviz config with its view replaced by a top-down orthographic one: `scale` pixels per metre,
    the fixed frame's point `focus` (x, y) at the centre of the render panel."""
    view = ("  Views:\n    Current:\n      Angle: 0\n      Class: rviz/TopDownOrtho\n      Invert Z Axis: false\n"
            "      Name: Current View\n      Near Clip Distance: 0.01\n      Scale: %g\n"
            "      Target Frame: <Fixed Frame>\n      X: %g\n      Y: %g\n    Saved: ~\n" % (scale, focus[0], focus[1]))
    text, n = re.subn(r"  Views:\n    Current:\n(?:      .*\n|        .*\n)*    Saved: ~\n", view, config_text)
    if n != 1:
        raise ValueError("the rviz config has no Views section to replace")
    return text


def rviz_command(config, log):
    """The shell command that starts rviz full screen (the render panel is the whole screen)."""
    return 'rviz --fullscreen -d "%s" > "%s" 2>&1' % (config, log)


class Screen(object):
    """A full-screen rviz screenshot of a top_down_config view and its world -> pixel map."""

    def __init__(self, path, scale, focus):
        self.width, self.height, self.rows = xwd_image.read_xwd(path)
        self.scale, self.focus = scale, focus
        self.cx, self.cy = (self.width - 1) / 2.0, (self.height - 1) / 2.0

    def at(self, x, y):
        """(r, g, b) of the fixed frame's point (x, y)."""
        px = int(round(self.cx + (x - self.focus[0]) * self.scale))
        py = int(round(self.cy - (y - self.focus[1]) * self.scale))
        return xwd_image.pixel(self.rows, px, py)

    def ring(self, centre, r0, r1, step=0.05):
        """The pixels of the points of a polar lattice between radii r0 and r1 around centre."""
        out = []
        r = r0
        while r <= r1:
            n = max(8, int(2 * math.pi * r / step))
            out += [self.at(centre[0] + r * math.cos(2 * math.pi * k / n), centre[1] + r * math.sin(2 * math.pi * k / n))
                    for k in range(n)]
            r += step
        return out

    def write_png(self, path):
        xwd_image.write_png(path, self.width, self.height, self.rows)


def grey(c, lo, hi):
    """A grey (r = g = b within 6) with every channel in [lo, hi]."""
    return max(c) - min(c) <= 6 and lo <= min(c) and max(c) <= hi
