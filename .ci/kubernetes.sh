#!/usr/bin/env bash
# The Kubernetes manifests (deploy/kubernetes/), validated offline:
#  - every Kubernetes object against the API's own schemas with kubernetes-validate
#    (PyPI; it bundles them), strictly (an unknown or misspelt field fails), for the
#    oldest release the worker's pod spec needs (1.33: user namespaces and
#    `procMount: Unmasked` on by default) and the newest the validator knows;
#  - KEDA's objects (ScaledObject, TriggerAuthentication) against KEDA's CRD schemas
#    (@kubernetes-models/keda from npm);
#  - every file is listed in kustomization.yaml, and every object validated by one of
#    the two (none skipped as an unknown kind).
# What the manifests say about the binary (image, flags, variables, grace periods,
# resources), the scaler's query on a real PostgreSQL and the workers' SIGTERM are
# tested by the integration tests (tests/it/deploy.rs).
#
#   bash .ci/kubernetes.sh        (needs python3 with venv, and Node.js with npm)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=deploy/kubernetes
tools=$(mktemp -d)
trap 'rm -rf "$tools"' EXIT
python3 -m venv "$tools/venv"
"$tools/venv/bin/pip" install -q kubernetes-validate==1.37.0
(cd "$tools" && npm init -y >/dev/null && npm install --silent --no-audit --no-fund @kubernetes-models/keda@2.0.0 js-yaml@4.1.0 >/dev/null 2>&1)

files=()
for f in "$dir"/*.yaml; do
  [ "$(basename "$f")" = kustomization.yaml ] && continue
  grep -qx "  - $(basename "$f")" "$dir/kustomization.yaml" || { echo "kubernetes: $f is not in kustomization.yaml's resources" >&2; exit 1; }
  files+=("$f")
done

for version in 1.33.0 1.37.0; do
  out=$("$tools/venv/bin/kubernetes-validate" --strict -k "$version" "${files[@]}" 2>&1) || { echo "$out" >&2; echo "kubernetes: the manifests do not validate against Kubernetes $version" >&2; exit 1; }
  echo "$out" | grep -v "^INFO" | grep -v "Couldn't find schema for kind \(ScaledObject\|TriggerAuthentication\) with api version keda.sh/v1alpha1" && { echo "kubernetes: unexpected warnings above" >&2; exit 1; }
  echo "kubernetes: $(echo "$out" | grep -c '^INFO.*passed') objects valid for Kubernetes $version"
done

cat >"$tools/keda.mjs" <<'JS'
import fs from "node:fs";
import * as yaml from "js-yaml";
import { ScaledObject } from "@kubernetes-models/keda/keda.sh/v1alpha1/ScaledObject";
import { TriggerAuthentication } from "@kubernetes-models/keda/keda.sh/v1alpha1/TriggerAuthentication";
const kinds = { ScaledObject, TriggerAuthentication };
let checked = 0, failed = 0;
for (const file of process.argv.slice(2)) {
  for (const doc of yaml.loadAll(fs.readFileSync(file, "utf8"))) {
    if (!doc || doc.apiVersion !== "keda.sh/v1alpha1") continue;
    const Kind = kinds[doc.kind];
    if (!Kind) { console.error(`${file}: no KEDA schema here for ${doc.kind}`); failed++; continue; }
    try { new Kind(doc).validate(); checked++; }
    catch (e) { console.error(`${file}: ${doc.kind}/${doc.metadata?.name}: ${e.message}`); failed++; }
  }
}
console.log(`kubernetes: ${checked} KEDA objects valid against KEDA's CRD schemas`);
if (failed || checked === 0) process.exit(1);
JS
abs=()
for f in "${files[@]}"; do abs+=("$PWD/$f"); done
(cd "$tools" && node keda.mjs "${abs[@]}")
