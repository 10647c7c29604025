#!/usr/bin/python3
"""A third-party Modbus TCP drive for ModbusBench's tests, written with
Debian's pymodbus (python3-pymodbus 3.0, run with /usr/bin/python3).

It follows conventions other than the simulated bench's, as described by
tests/motion/pymodbus_drive.toml: every register is a holding register,
32-bit values are LOW word first, positions are in 0.01 mm, speed in
0.01 mm/s, IAI-like status bits (PEND = in position), other command codes.
Motion is a constant-speed ramp per axis, computed from the clock when the
registers are read.

Usage: pymodbus_drive.py [PORT]   (0 or absent: an ephemeral port)
Prints "PORT <n>" once listening; stops on SIGTERM or SIGINT.
"""
import asyncio
import logging
import signal
import sys
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer

# The map, as in pymodbus_drive.toml (0-based addresses).
TARGET_X, TARGET_Y, SPEED, COMMAND = 0x100, 0x102, 0x104, 0x105
ACTUAL_X, ACTUAL_Y, STATUS, ALARM = 0x200, 0x202, 0x204, 0x205
PEND, HEND, MOVE, ALM = 1 << 3, 1 << 4, 1 << 5, 1 << 10
CMD_MOVE, CMD_HOME, CMD_STOP, CMD_RESET = 0x11, 0x12, 0x13, 0x14
ALARM_NOT_HOMED = 4


def to_words(counts):
    """int32 -> [low, high] (low word first)."""
    u = counts & 0xFFFFFFFF
    return [u & 0xFFFF, u >> 16]


def from_words(words):
    u = words[0] | (words[1] << 16)
    return u - (1 << 32) if u & 0x80000000 else u


class Axis:
    def __init__(self):
        self.start = self.target = 0  # counts (0.01 mm)
        self.t0 = 0.0
        self.speed = 1.0  # counts per s

    def at(self, now):
        span = self.target - self.start
        if span == 0:
            return self.target
        done = min(1.0, (now - self.t0) * self.speed / abs(span))
        return round(self.start + span * done)

    def go(self, now, target, speed):
        self.start, self.target, self.t0, self.speed = self.at(now), target, now, max(speed, 1)


class Drive(ModbusSequentialDataBlock):
    """Holding registers with the drive's behaviour behind them."""

    def __init__(self):
        super().__init__(0, [0] * 0x300)
        self.x, self.y = Axis(), Axis()
        self.homed, self.alarm = False, 0
        self.x.start = self.x.target = 2000  # power-up at (20, 20) mm
        self.y.start = self.y.target = 2000

    def getValues(self, address, count=1):
        now = time.monotonic()
        x, y = self.x.at(now), self.y.at(now)
        moving = (x, y) != (self.x.target, self.y.target)
        status = (HEND if self.homed else 0) | (MOVE if moving else 0)
        targets = super().getValues(TARGET_X, 4)
        if not moving and [x, y] == [from_words(targets[0:2]), from_words(targets[2:4])]:
            status |= PEND
        if self.alarm:
            status |= ALM
        super().setValues(ACTUAL_X, to_words(x) + to_words(y) + [status, self.alarm])
        return super().getValues(address, count)

    def setValues(self, address, values):
        values = values if isinstance(values, list) else [values]
        super().setValues(address, values)
        if address <= COMMAND < address + len(values):
            self.command(values[COMMAND - address])

    def command(self, code):
        now = time.monotonic()
        regs = super().getValues(TARGET_X, 6)
        speed = regs[4]  # 0.01 mm/s = counts/s
        if code == CMD_MOVE and not self.alarm:
            if not self.homed:
                self.alarm = ALARM_NOT_HOMED
                return
            self.x.go(now, from_words(regs[0:2]), speed)
            self.y.go(now, from_words(regs[2:4]), speed)
        elif code == CMD_HOME and not self.alarm:
            self.x.go(now, 0, 10000)
            self.y.go(now, 0, 10000)
            self.homed = True
            super().setValues(TARGET_X, to_words(0) + to_words(0))
        elif code == CMD_STOP:
            for axis in (self.x, self.y):
                axis.go(now, axis.at(now), axis.speed)
        elif code == CMD_RESET:
            self.alarm = 0


async def main():
    # pymodbus logs every client that hangs up as an error; they are not.
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    port = int(sys.argv[1]) if len(sys.argv) > 1 else 0
    context = ModbusServerContext(
        slaves=ModbusSlaveContext(hr=Drive(), zero_mode=True), single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", port), allow_reuse_address=True)
    task = asyncio.create_task(server.serve_forever())
    await server.serving
    print("PORT", server.server.sockets[0].getsockname()[1], flush=True)
    stop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        asyncio.get_running_loop().add_signal_handler(sig, stop.set)
    await stop.wait()
    await server.shutdown()
    task.cancel()


if __name__ == "__main__":
    asyncio.run(main())
