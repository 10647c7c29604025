#!/usr/bin/python3
"""Two single-axis Modbus TCP drives, an X drive and a Y drive, for the tests
of a bench of two drives (tests/motion/two_drive_test.cpp), written with
Debian's pymodbus (python3-pymodbus 3.0, run with /usr/bin/python3). The
profile that drives them is tests/motion/axis_drives.toml.

The two drives follow different conventions, as two drives of two makers do:
  X drive: every register holding; target 0x100-0x101 and read-back
           0x200-0x201 LOW word first in 0.01 mm; speed 0x102 in 0.01 mm/s;
           command register 0x103 keeps its code (1 move, 2 home, 3 stop,
           4 reset alarm); status 0x202 (IAI-like: PEND 3, HEND 4, MOVE 5,
           ALM 10, EMGS 15), alarm code 0x203. Travel 0..200 mm.
  Y drive: target 0x10-0x11 HIGH word first in micrometres, speed 0x12 in
           0.1 mm/s, control word 0x13 of bits the drive clears once taken
           (START 0, HOME 1, STOP 2, RESET 3); read-back 0x20-0x21 (high
           first, um), status 0x22 (HOMED 0, BUSY 1, INPOS 2, ALARM 3, ESTOP
           4) and alarm code 0x23 are INPUT registers. Travel 0..100 mm.
Each drive raises alarm 4 on a move before homing, and its own overtravel
alarm on a target outside its travel (X: 0x0A, Y: 0x31), and stays where it
is. Motion is a constant-speed ramp computed from the clock.

Links: by default one port serves both drives, X at unit 1 and Y at unit 2
(--x-unit, --y-unit); with --two-ports each drive has a port of its own, and
any unit id reaches it. The first line printed is "PORTS <x port> <y port>".

Faults: SIGUSR1 drops the Y drive's link for --drop-s seconds (default 0.3):
with --two-ports its connections are closed and its port stops listening;
on one port the Y unit stops answering (the X unit answers on). SIGTERM or
SIGINT stops the emulator.

Usage: axis_drives.py [--two-ports] [--x-unit N] [--y-unit N] [--drop-s S]
"""
import argparse
import asyncio
import logging
import signal
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.exceptions import NoSuchSlaveException
from pymodbus.server.async_io import ModbusTcpServer

ALARM_NOT_HOMED = 4


class Axis:
    """Constant-speed ramp in counts, computed from the clock."""

    def __init__(self, counts):
        self.start = self.target = counts
        self.t0, self.speed = 0.0, 1.0

    def at(self, now):
        span = self.target - self.start
        if span == 0:
            return self.target
        return round(self.start + span * min(1.0, (now - self.t0) * self.speed / abs(span)))

    def go(self, now, target, speed):
        self.start, self.target, self.t0, self.speed = self.at(now), target, now, max(speed, 1)

    def halt(self, now):
        self.go(now, self.at(now), self.speed)


def words(counts, low_first):
    u = counts & 0xFFFFFFFF
    return [u & 0xFFFF, u >> 16] if low_first else [u >> 16, u & 0xFFFF]


def counts_of(regs, low_first):
    lo, hi = (regs[0], regs[1]) if low_first else (regs[1], regs[0])
    u = lo | (hi << 16)
    return u - (1 << 32) if u & 0x80000000 else u


class XDrive(ModbusSequentialDataBlock):
    """The X drive: holding registers only, a command register that keeps its code."""

    TARGET, SPEED, COMMAND = 0x100, 0x102, 0x103
    ACTUAL, STATUS, ALARM = 0x200, 0x202, 0x203
    PEND, HEND, MOVE, ALM = 1 << 3, 1 << 4, 1 << 5, 1 << 10
    MOVE_CMD, HOME_CMD, STOP_CMD, RESET_CMD = 1, 2, 3, 4
    TRAVEL = (0, 20000)  # counts (0.01 mm)
    OVERTRAVEL = 0x0A

    def __init__(self):
        super().__init__(0, [0] * 0x300)
        self.axis = Axis(2000)  # power-up at 20 mm
        self.homed, self.alarm = False, 0

    def getValues(self, address, count=1):
        now = time.monotonic()
        pos = self.axis.at(now)
        moving = pos != self.axis.target
        status = (self.HEND if self.homed else 0) | (self.MOVE if moving else 0)
        target = counts_of(super().getValues(self.TARGET, 2), True)
        if not moving and pos == target:
            status |= self.PEND
        status |= self.ALM if self.alarm else 0
        super().setValues(self.ACTUAL, words(pos, True) + [status, self.alarm])
        return super().getValues(address, count)

    def setValues(self, address, values):
        values = values if isinstance(values, list) else [values]
        super().setValues(address, values)
        if address <= self.COMMAND < address + len(values):
            self.command(values[self.COMMAND - address])

    def command(self, code):
        now = time.monotonic()
        if code == self.RESET_CMD:
            self.alarm = 0
        elif code == self.STOP_CMD:
            self.axis.halt(now)
        elif self.alarm:
            return
        elif code == self.HOME_CMD:
            self.axis.go(now, 0, 10000)
            self.homed = True
            super().setValues(self.TARGET, words(0, True))
        elif code == self.MOVE_CMD:
            target = counts_of(super().getValues(self.TARGET, 2), True)
            if not self.homed:
                self.alarm = ALARM_NOT_HOMED
            elif not self.TRAVEL[0] <= target <= self.TRAVEL[1]:
                self.alarm = self.OVERTRAVEL
            else:
                self.axis.go(now, target, super().getValues(self.SPEED, 1)[0])


class YDrive(ModbusSequentialDataBlock):
    """The Y drive's holding registers: targets and a control word it clears."""

    TARGET, SPEED, CONTROL = 0x10, 0x12, 0x13
    START, HOME, STOP, RESET = 1 << 0, 1 << 1, 1 << 2, 1 << 3
    HOMED, BUSY, INPOS, ALARM_BIT = 1 << 0, 1 << 1, 1 << 2, 1 << 3
    TRAVEL = (0, 100000)  # counts (um)
    OVERTRAVEL = 0x31

    def __init__(self):
        super().__init__(0, [0] * 0x40)
        self.axis = Axis(20000)  # power-up at 20 mm
        self.homed, self.alarm = False, 0

    def setValues(self, address, values):
        values = values if isinstance(values, list) else [values]
        super().setValues(address, values)
        if address <= self.CONTROL < address + len(values):
            self.control(values[self.CONTROL - address])
            super().setValues(self.CONTROL, [0])  # taken: the drive clears it

    def control(self, bits):
        now = time.monotonic()
        if bits & self.RESET:
            self.alarm = 0
        if bits & self.STOP:
            self.axis.halt(now)
        if self.alarm:
            return
        if bits & self.HOME:
            self.axis.go(now, 0, 100000)
            self.homed = True
            super().setValues(self.TARGET, words(0, False))
        elif bits & self.START:
            target = counts_of(super().getValues(self.TARGET, 2), False)
            if not self.homed:
                self.alarm = ALARM_NOT_HOMED
            elif not self.TRAVEL[0] <= target <= self.TRAVEL[1]:
                self.alarm = self.OVERTRAVEL
            else:
                speed = super().getValues(self.SPEED, 1)[0] * 100  # 0.1 mm/s -> um/s
                self.axis.go(now, target, speed)

    def feedback(self):
        now = time.monotonic()
        pos = self.axis.at(now)
        moving = pos != self.axis.target
        target = counts_of(super().getValues(self.TARGET, 2), False)
        status = (self.HOMED if self.homed else 0) | (self.BUSY if moving else 0)
        if not moving and pos == target:
            status |= self.INPOS
        status |= self.ALARM_BIT if self.alarm else 0
        return words(pos, False) + [status, self.alarm]


class YFeedback(ModbusSequentialDataBlock):
    """The Y drive's input registers: read-back, status and alarm at 0x20."""

    def __init__(self, drive):
        super().__init__(0, [0] * 0x40)
        self.drive = drive

    def getValues(self, address, count=1):
        super().setValues(0x20, self.drive.feedback())
        return super().getValues(address, count)


class Units(ModbusServerContext):
    """Unit ids to drives; a silenced unit does not answer (a dead link)."""

    def __init__(self, slaves):
        super().__init__(slaves=slaves, single=False)
        self.silent = set()

    def __getitem__(self, unit):
        if unit in self.silent:
            raise NoSuchSlaveException(f"unit {unit} silenced")
        return super().__getitem__(unit)


def y_context():
    y = YDrive()
    return ModbusSlaveContext(hr=y, ir=YFeedback(y), zero_mode=True)


async def serve(context, port=0):
    server = ModbusTcpServer(context, address=("127.0.0.1", port), allow_reuse_address=True,
                             ignore_missing_slaves=True)
    asyncio.create_task(server.serve_forever())
    await server.serving
    return server


async def close(server):
    for conn in list(server.active_connections.values()):
        transport = getattr(conn, "transport", None)
        if transport is not None:
            transport.close()
    await server.server_close()


async def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--two-ports", action="store_true")
    parser.add_argument("--x-unit", type=int, default=1)
    parser.add_argument("--y-unit", type=int, default=2)
    parser.add_argument("--drop-s", type=float, default=0.3)
    args = parser.parse_args()
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    x = ModbusSlaveContext(hr=XDrive(), zero_mode=True)
    y = y_context()
    if args.two_ports:
        x_server = await serve(ModbusServerContext(slaves=x, single=True))
        y_context_ = ModbusServerContext(slaves=y, single=True)
        y_server = await serve(y_context_)
        x_port = x_server.server.sockets[0].getsockname()[1]
        y_port = y_server.server.sockets[0].getsockname()[1]
        units = None
    else:
        units = Units({args.x_unit: x, args.y_unit: y})
        x_server = y_server = await serve(units)
        x_port = y_port = x_server.server.sockets[0].getsockname()[1]
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    drop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    loop.add_signal_handler(signal.SIGUSR1, drop.set)
    print("PORTS", x_port, y_port, flush=True)  # after the handlers: a fault may follow at once
    while not stop.is_set():
        waiter = asyncio.create_task(drop.wait())
        stopper = asyncio.create_task(stop.wait())
        await asyncio.wait({waiter, stopper}, return_when=asyncio.FIRST_COMPLETED)
        waiter.cancel()
        stopper.cancel()
        if not drop.is_set():
            continue
        drop.clear()
        if units is not None:
            units.silent.add(args.y_unit)
            await asyncio.sleep(args.drop_s)
            units.silent.discard(args.y_unit)
        else:
            await close(y_server)
            await asyncio.sleep(args.drop_s)
            y_server = await serve(y_context_, y_port)
    await close(x_server)
    if y_server is not x_server:
        await close(y_server)


if __name__ == "__main__":
    asyncio.run(main())
