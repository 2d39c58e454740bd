#!/bin/sh
# Health check of a render node (`naadf render-node`), which listens on no port of its own:
# healthy while it holds an established TCP connection to the server's gRPC port, read from
# /proc/net/tcp{,6}. The node reconnects by itself, so this says "connected", not "alive":
# use it for readiness and for `docker compose ps`, not to restart the node.
#
# The port comes from NAADF_SERVER (`http://HOST:PORT` or `https://HOST[:PORT]`), or the
# first argument; the default is the CLI's, 50051.
set -eu
url="${1:-${NAADF_SERVER:-http://127.0.0.1:50051}}"
rest="${url#*://}"
hostport="${rest%%/*}"
case "$hostport" in
    *\]:*) port="${hostport##*]:}" ;;           # [v6]:port
    *\]) port="" ;;                               # [v6]
    *:*) port="${hostport##*:}" ;;
    *) port="" ;;
esac
if [ -z "$port" ]; then
    case "$url" in https://*) port=443 ;; *) port=80 ;; esac
fi
hex=$(printf '%04X' "$port")
# Fields: sl local_address rem_address st ...; state 01 is ESTABLISHED.
if awk -v want=":$hex" 'FNR > 1 && substr($3, length($3) - 4) == want && $4 == "01" { found = 1 } END { exit !found }' \
    /proc/net/tcp /proc/net/tcp6 2>/dev/null; then
    exit 0
fi
echo "not connected to the server's port $port" >&2
exit 1
