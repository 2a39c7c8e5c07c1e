#!/usr/bin/env python3
"""A slow, lossy point-to-point link between two network namespaces, in user space: what
`tc qdisc add dev X root netem delay D J loss L` on both ends of a veth pair does, for kernels built
without sch_netem (CONFIG_NET_SCH_NETEM unset, as on the CI machine).

    link_emulator.py NS_A ADDR_A/PREFIX NS_B ADDR_B/PREFIX --delay-ms 50 --jitter-ms 10 --loss 0.02

creates a TUN device in each namespace (named tunlA/tunlB unless --names), gives them the addresses,
and forwards every IP packet between them after a delay drawn uniformly from delay +- jitter (so
packets may be reordered, as with netem), dropping each one with probability `loss`, in both
directions. Prints "ready" when the link is up. The devices vanish when the process ends. Needs root.
"""
import argparse
import ctypes
import fcntl
import heapq
import os
import random
import select
import struct
import subprocess
import sys
import time

CLONE_NEWNET = 0x40000000
TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000

_libc = ctypes.CDLL(None, use_errno=True)


def enter_netns(name):
    fd = os.open(os.path.join("/var/run/netns", name), os.O_RDONLY)
    try:
        if _libc.setns(fd, CLONE_NEWNET) != 0:
            err = ctypes.get_errno()
            raise OSError(err, "setns into network namespace %s: %s" % (name, os.strerror(err)))
    finally:
        os.close(fd)


def open_tun(ifname):
    fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", ifname.encode(), IFF_TUN | IFF_NO_PI))
    return fd


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ns_a")
    ap.add_argument("addr_a")
    ap.add_argument("ns_b")
    ap.add_argument("addr_b")
    ap.add_argument("--delay-ms", type=float, default=50.0)
    ap.add_argument("--jitter-ms", type=float, default=10.0)
    ap.add_argument("--loss", type=float, default=0.02, help="drop probability per packet [0..1)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--names", nargs=2, default=("tunlA", "tunlB"), metavar=("IF_A", "IF_B"))
    a = ap.parse_args()
    if not (0.0 <= a.loss < 1.0):
        ap.error("--loss %g must be in [0, 1)" % a.loss)
    if a.delay_ms < 0 or a.jitter_ms < 0 or a.jitter_ms > a.delay_ms:
        ap.error("need 0 <= jitter (%g ms) <= delay (%g ms)" % (a.jitter_ms, a.delay_ms))

    home = os.open("/proc/self/ns/net", os.O_RDONLY)
    enter_netns(a.ns_a)
    fd_a = open_tun(a.names[0])
    enter_netns(a.ns_b)
    fd_b = open_tun(a.names[1])
    _libc.setns(home, CLONE_NEWNET)
    for ns, ifname, addr in ((a.ns_a, a.names[0], a.addr_a), (a.ns_b, a.names[1], a.addr_b)):
        subprocess.run(["ip", "-n", ns, "addr", "add", addr, "dev", ifname], check=True)
        subprocess.run(["ip", "-n", ns, "link", "set", ifname, "up"], check=True)
    print("ready", flush=True)

    rng = random.Random(a.seed)
    other = {fd_a: fd_b, fd_b: fd_a}
    queue = []  # (due time, sequence, destination fd, packet)
    seq = 0
    forwarded = dropped = 0
    while True:
        now = time.monotonic()
        while queue and queue[0][0] <= now:
            _, _, dst, pkt = heapq.heappop(queue)
            try:
                os.write(dst, pkt)
                forwarded += 1
            except OSError:
                pass  # the device is down: the packet is lost, as on a real link
        timeout = max(0.0, queue[0][0] - now) if queue else 1.0
        readable, _, _ = select.select([fd_a, fd_b], [], [], timeout)
        for fd in readable:
            while True:
                try:
                    pkt = os.read(fd, 65536)
                except BlockingIOError:
                    break
                if rng.random() < a.loss:
                    dropped += 1
                    continue
                delay = (a.delay_ms + rng.uniform(-a.jitter_ms, a.jitter_ms)) / 1000.0
                seq += 1
                heapq.heappush(queue, (time.monotonic() + delay, seq, other[fd], pkt))


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(0)
