#!/usr/bin/python3
"""A pymodbus 3.0 server for the benchmarks: Debian's python3-pymodbus, run by
/usr/bin/python3, its asyncio TCP server (StartAsyncTcpServer) answering from
a plain datastore of 1000 coils, discrete inputs, holding and input registers
(all zero) for any unit id.

    /usr/bin/python3 bench/pymodbus_server.py --port 1502

Prints a line containing "listening" once the socket accepts connections.
"""
import argparse
import asyncio
import logging
import sys
import types

# Debian's pymodbus 3.0 imports serial_asyncio for its serial classes even when
# only TCP is used; tools/install-deps.sh installs python3-serial-asyncio, this
# stub only keeps a machine without it working.
try:
    import serial_asyncio  # noqa: F401
except ImportError:
    _stub = types.ModuleType("serial_asyncio")
    _stub.create_serial_connection = None
    sys.modules["serial_asyncio"] = _stub

from pymodbus.datastore import (ModbusSequentialDataBlock, ModbusServerContext,
                                ModbusSlaveContext)
from pymodbus.server import StartAsyncTcpServer


async def main():
    p = argparse.ArgumentParser()
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=1502)
    args = p.parse_args()
    logging.disable(logging.CRITICAL)  # a client closing its connection is logged as an error

    def block():
        return ModbusSequentialDataBlock(0, [0] * 1000)

    slave = ModbusSlaveContext(di=block(), co=block(), hr=block(), ir=block(), zero_mode=True)
    context = ModbusServerContext(slaves=slave, single=True)
    server = await StartAsyncTcpServer(context=context, address=(args.host, args.port),
                                       allow_reuse_address=True, defer_start=True, backlog=128)
    serve = asyncio.create_task(server.serve_forever())
    await server.serving
    print(f"pymodbus_server: listening on tcp {args.host}:{args.port}", flush=True)
    await serve


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        pass
