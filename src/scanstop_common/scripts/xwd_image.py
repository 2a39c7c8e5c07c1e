"""Reads an X window dump (xwd -root, 24/32-bit TrueColor) and writes it as PNG; no imaging library.
The screenshot tests of rviz (scanstop_sim, scanstop_mesher) read their screenshots with it and look at
what a user sees: where the render panel is, and what colour a world point has on it."""
import struct
import zlib


def read_xwd(path):
    """Returns (width, height, rows) with rows a list of bytes objects, RGB, 3 bytes per pixel."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 100:
        raise ValueError("%s: %d bytes, not a window dump" % (path, len(data)))
    fields = struct.unpack(">25I", data[:100])
    header_size, version = fields[0], fields[1]
    if version != 7:
        raise ValueError("%s: xwd version %d, expected 7" % (path, version))
    width, height = fields[4], fields[5]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    red_mask, green_mask, blue_mask = fields[14], fields[15], fields[16]
    ncolors = fields[19]
    # Xvfb reports 24 bits per pixel but stores 4 bytes per pixel (bitmap_unit 32).
    if bits_per_pixel not in (24, 32) or bytes_per_line < 4 * width:
        raise ValueError("%s: %d bits per pixel, %d bytes per line for %d pixels: not 32-bit TrueColor" %
                         (path, bits_per_pixel, bytes_per_line, width))
    offset = header_size + 12 * ncolors
    if len(data) < offset + bytes_per_line * height:
        raise ValueError("%s: truncated" % path)
    fmt = ("<" if byte_order == 0 else ">") + "%dI" % width

    def shift(mask):
        s = 0
        while mask and not mask & 1:
            mask >>= 1
            s += 1
        return s

    rs, gs, bs = shift(red_mask), shift(green_mask), shift(blue_mask)
    rows = []
    for y in range(height):
        start = offset + y * bytes_per_line
        px = struct.unpack(fmt, data[start:start + 4 * width])
        row = bytearray(3 * width)
        row[0::3] = bytes(((p & red_mask) >> rs) & 0xFF for p in px)
        row[1::3] = bytes(((p & green_mask) >> gs) & 0xFF for p in px)
        row[2::3] = bytes(((p & blue_mask) >> bs) & 0xFF for p in px)
        rows.append(bytes(row))
    return width, height, rows


def write_png(path, width, height, rows):
    def chunk(tag, body):
        c = struct.pack(">I", len(body)) + tag + body
        return c + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + r for r in rows)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def distinct_colors(rows, step=4):
    """Number of distinct RGB values over every step-th pixel of every step-th row."""
    seen = set()
    for r in rows[::step]:
        for x in range(0, len(r) - 2, 3 * step):
            seen.add(r[x:x + 3])
    return len(seen)


def pixel(rows, x, y):
    """(r, g, b) at column x, row y."""
    row = rows[y]
    return row[3 * x], row[3 * x + 1], row[3 * x + 2]


def bounding_box(width, height, rows, colour, tolerance=2):
    """(x0, y0, x1, y1) of the pixels within `tolerance` of `colour` (inclusive), or None. rviz's
    render panel is the box of its background colour when the scene leaves some of it free all round."""
    r0, g0, b0 = colour
    xs, ys = [], []
    for y in range(height):
        row = rows[y]
        for x in range(0, width, 2):  # every other column is enough for a box
            if abs(row[3 * x] - r0) <= tolerance and abs(row[3 * x + 1] - g0) <= tolerance and \
                    abs(row[3 * x + 2] - b0) <= tolerance:
                xs.append(x)
                ys.append(y)
                break
        else:
            continue
        for x in range(width - 1, -1, -2):
            if abs(row[3 * x] - r0) <= tolerance and abs(row[3 * x + 1] - g0) <= tolerance and \
                    abs(row[3 * x + 2] - b0) <= tolerance:
                xs.append(x)
                break
    if not xs:
        return None
    return min(xs), min(ys), max(xs), max(ys)
