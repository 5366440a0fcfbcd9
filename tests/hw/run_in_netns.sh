#!/bin/sh
# Runs a test program inside a network namespace of its own (unshare -rn): the GigE Vision simulators bind
# 127.0.0.1 and 127.0.0.2 on a private loopback, so they cannot clash with other tests or a camera network.
# Where the kernel refuses the namespace the test is reported as skipped (exit 77) with the reason, never silently.
if ! unshare -rn true 2>/dev/null; then
  echo "SKIPPED: the kernel refuses an unprivileged network namespace (unshare -rn); the GigE Vision simulator tests need one" >&2
  exit 77
fi
exec unshare -rn sh -c 'ip link set lo up && ip addr add 127.0.0.2/8 dev lo && exec "$@"' sh "$@"
