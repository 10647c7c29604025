#!/usr/bin/python3
"""A Modbus TCP drive with a bit-coded control word, for the handshake tests of
ModbusBench (tests/motion/handshake_test.cpp), written with Debian's pymodbus
(python3-pymodbus 3.0, run with /usr/bin/python3).

Its conventions are those of many third-party drives (docs/drive-profile.md,
[handshake]): every register is a holding register, 32-bit values LOW word
first (or, with --position-bits 16, one signed register per position),
0.01 mm counts, IAI-like status bits, and a control word of bits:
  bit 0 CSTR start positioning, bit 1 HOME, bit 2 STP stop, bit 3 RES alarm
  reset, bit 4 SON servo on (kept set while the servo is to stay on).
--control says how the drive takes a command bit:
  clears: it acts on every write with the bit set, then clears the command
          bits itself (SON stays), so the register never reads back as written;
  edge:   it acts on the rising edge of a bit only, sets ACK (status bit 6)
          while a bit it took is still set, and ignores a bit that stays set.
--servo: moves and homing need SON and the servo ready (SV, status bit 7,
          50 ms after SON); a command without it raises alarm 0xB1; SON
          dropped while the servo is on stops the drive with alarm 0xB1.
Without --servo, SV reads 1. A move before homing raises alarm 4. RES clears
an alarm on its rising edge (clears: on every write with RES).

Usage: handshake_drive.py PORT --control clears|edge [--servo] [--position-bits 16]
(PORT 0: an ephemeral port). Prints "PORT <n>" once listening; stops on
SIGTERM or SIGINT.
"""
import argparse
import asyncio
import logging
import signal
import time

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server.async_io import ModbusTcpServer

TARGET_X, SPEED, CONTROL = 0x100, 0x104, 0x105
ACTUAL_X, STATUS, ALARM = 0x200, 0x204, 0x205
CSTR, HOME, STP, RES, SON = 1 << 0, 1 << 1, 1 << 2, 1 << 3, 1 << 4
COMMAND_BITS = CSTR | HOME | STP | RES
PEND, HEND, MOVE, ACK, SV, ALM = 1 << 3, 1 << 4, 1 << 5, 1 << 6, 1 << 7, 1 << 10
ALARM_NOT_HOMED, ALARM_SERVO_OFF = 4, 0xB1
SERVO_DELAY_S = 0.05


class Axis:
    """Constant-speed ramp, computed from the clock."""

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


class Drive(ModbusSequentialDataBlock):
    def __init__(self, control, servo, position_bits):
        super().__init__(0, [0] * 0x300)
        self.control_mode, self.servo, self.words = control, servo, position_bits // 16
        self.x, self.y = Axis(2000), Axis(2000)  # power-up at (20, 20) mm
        self.homed, self.alarm = False, 0
        self.servo_on_since = None  # time SON was set, None while off
        self.taken = 0  # edge mode: command bits taken and still set

    def encode(self, counts):
        u = counts & 0xFFFFFFFF
        return [u & 0xFFFF, u >> 16] if self.words == 2 else [counts & 0xFFFF]

    def decode(self, regs):
        if self.words == 1:
            return regs[0] - (1 << 16) if regs[0] & 0x8000 else regs[0]
        u = regs[0] | (regs[1] << 16)
        return u - (1 << 32) if u & 0x80000000 else u

    def targets(self):
        regs = super().getValues(TARGET_X, 4)
        return self.decode(regs[0:]), self.decode(regs[2 if self.words == 2 else 1:])

    def servo_ready(self, now):
        if not self.servo:
            return True
        return self.servo_on_since is not None and now - self.servo_on_since >= SERVO_DELAY_S

    def getValues(self, address, count=1):
        now = time.monotonic()
        x, y = self.x.at(now), self.y.at(now)
        moving = (x, y) != (self.x.target, self.y.target)
        status = (HEND if self.homed else 0) | (MOVE if moving else 0)
        if not moving and (x, y) == self.targets():
            status |= PEND
        status |= (ALM if self.alarm else 0) | (SV if self.servo_ready(now) else 0)
        status |= ACK if self.taken else 0
        # X then Y: at 0x200 and 0x202 (32-bit), or at 0x200 and 0x201 (16-bit).
        super().setValues(ACTUAL_X, self.encode(x) + self.encode(y))
        super().setValues(STATUS, [status, self.alarm])
        return super().getValues(address, count)

    def setValues(self, address, values):
        values = values if isinstance(values, list) else [values]
        old = super().getValues(CONTROL, 1)[0]
        super().setValues(address, values)
        if address <= CONTROL < address + len(values):
            self.control(old, values[CONTROL - address])

    def control(self, old, new):
        now = time.monotonic()
        if self.servo:
            if new & SON and self.servo_on_since is None:
                self.servo_on_since = now
            elif not new & SON and self.servo_on_since is not None:
                self.servo_on_since = None
                self.halt(now)
                self.alarm = self.alarm or ALARM_SERVO_OFF
        if self.control_mode == "edge":
            act = new & ~old & COMMAND_BITS
            self.taken = (self.taken | act) & new
        else:  # clears
            act = new & COMMAND_BITS
            super().setValues(CONTROL, [new & ~COMMAND_BITS])
        if act & RES:
            self.alarm = 0
        if act & STP:
            self.halt(now)
        if act & (CSTR | HOME):
            self.start(now, home=bool(act & HOME))

    def halt(self, now):
        for axis in (self.x, self.y):
            axis.go(now, axis.at(now), axis.speed)

    def start(self, now, home):
        if self.alarm:
            return
        if not self.servo_ready(now):
            self.alarm = ALARM_SERVO_OFF
            return
        if home:
            self.x.go(now, 0, 10000)
            self.y.go(now, 0, 10000)
            self.homed = True
            super().setValues(TARGET_X, self.encode(0) * 2)
            return
        if not self.homed:
            self.alarm = ALARM_NOT_HOMED
            return
        speed = super().getValues(SPEED, 1)[0]  # 0.01 mm/s = counts/s
        tx, ty = self.targets()
        self.x.go(now, tx, speed)
        self.y.go(now, ty, speed)


async def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("port", type=int)
    parser.add_argument("--control", choices=["clears", "edge"], required=True)
    parser.add_argument("--servo", action="store_true")
    parser.add_argument("--position-bits", type=int, choices=[16, 32], default=32)
    args = parser.parse_args()
    logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
    drive = Drive(args.control, args.servo, args.position_bits)
    context = ModbusServerContext(slaves=ModbusSlaveContext(hr=drive, zero_mode=True), single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", args.port), allow_reuse_address=True)
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
