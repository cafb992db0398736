"""Prints the podman options that give a container what a Deployment's pod spec gives
its first container: security context (pod and container), user namespace, resources,
volumes (each emptyDir a new folder under $TMPDIR), and the environment's literal values (values from Secrets are left to the
caller). Every field of the security contexts must be one this script knows how to give
podman: an unknown one fails, so the image test cannot pass on a pod spec it did not
reproduce.

    python3 .ci/kube_podman.py deploy/kubernetes/worker.yaml

Needs PyYAML (python3-yaml); reads the file's Deployment.
"""

import os
import shlex
import sys
import tempfile

import yaml


# The profiles a pod may lift, and podman's name for each.
PROFILES = {"seccompProfile": "seccomp", "appArmorProfile": "apparmor"}


def fail(message):
    sys.exit(f"kube_podman: {message}")


def memory_bytes(quantity):
    units = {"Ki": 1 << 10, "Mi": 1 << 20, "Gi": 1 << 30}
    for suffix, factor in units.items():
        if quantity.endswith(suffix):
            return int(quantity[: -len(suffix)]) * factor
    return int(quantity)


def options(deployment):
    pod = deployment["spec"]["template"]["spec"]
    container = pod["containers"][0]
    out = []
    user = group = non_root = None
    for key, value in pod.items():
        if key == "hostUsers":
            if value is False:
                # A user namespace of the pod's own: 65536 ids mapped to an unused range.
                out += ["--uidmap", "0:200000:65536", "--gidmap", "0:200000:65536"]
        elif key in ("automountServiceAccountToken", "enableServiceLinks", "terminationGracePeriodSeconds",
                     "containers", "volumes", "securityContext"):
            pass  # no podman counterpart needed (no service account, no services), or below
        else:
            fail(f"the pod spec's {key} is not reproduced")
    contexts = [pod.get("securityContext", {}), container.get("securityContext", {})]
    for context in contexts:
        for key, value in context.items():
            if key == "runAsUser":
                user = value
            elif key == "runAsGroup":
                group = value
            elif key == "runAsNonRoot":
                non_root = value
            elif key == "fsGroup":
                out += ["--group-add", str(value)]
            elif key in PROFILES:
                kind = value["type"]
                if kind == "Unconfined":
                    out += ["--security-opt", f"{PROFILES[key]}=unconfined"]
                elif kind != "RuntimeDefault":
                    fail(f"{key} {kind}")
            elif key == "procMount":
                if value == "Unmasked":
                    out += ["--security-opt", "unmask=ALL"]
                elif value != "Default":
                    fail(f"procMount {value}")
            elif key == "allowPrivilegeEscalation":
                if value is False:
                    out += ["--security-opt", "no-new-privileges"]
            elif key == "privileged":
                if value:
                    out += ["--privileged"]
            elif key == "capabilities":
                for cap in value.get("drop", []):
                    out += ["--cap-drop", cap]
                for cap in value.get("add", []):
                    out += ["--cap-add", cap]
            elif key == "readOnlyRootFilesystem":
                if value:
                    out += ["--read-only", "--read-only-tmpfs=false"]
            else:
                fail(f"the security context's {key} is not reproduced")
    if user is None:
        fail("no runAsUser")
    if non_root and user == 0:
        fail("runAsNonRoot with runAsUser 0")
    out += ["--user", f"{user}:{group if group is not None else user}"]
    limits = container.get("resources", {}).get("limits", {})
    if "memory" in limits:
        out += ["--memory", str(memory_bytes(limits["memory"]))]
    if "cpu" in limits:
        out += ["--cpus", str(limits["cpu"])]
    volumes = {v["name"]: v for v in pod.get("volumes", [])}
    for mount in container.get("volumeMounts", []):
        volume = volumes[mount["name"]]
        if "emptyDir" not in volume:
            fail(f"volume {mount['name']} is not an emptyDir")
        # An emptyDir: a new empty folder of the node's, writable by the pod (a tmpfs
        # over a folder the image has keeps that folder's owner and mode under podman).
        folder = tempfile.mkdtemp(prefix=f"emptydir-{mount['name']}-")
        os.chmod(folder, 0o1777)
        out += ["--mount", f"type=bind,source={folder},destination={mount['mountPath']}"]
    for env in container.get("env", []):
        if "value" in env:
            out += ["-e", f"{env['name']}={env['value']}"]
    return out


def main():
    with open(sys.argv[1]) as f:
        docs = [d for d in yaml.safe_load_all(f) if d and d.get("kind") == "Deployment"]
    if len(docs) != 1:
        fail(f"{sys.argv[1]} holds {len(docs)} Deployments, not 1")
    print(shlex.join(options(docs[0])))


if __name__ == "__main__":
    main()
