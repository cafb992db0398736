"""The README's podman examples, as the image test runs them.

    python3 .ci/readme_podman.py commands N   the Nth ```sh block under "#### With podman",
                                              one whole command a line (continuations joined)
    python3 .ci/readme_podman.py script N     the Nth block as the test runs it: `podman build`
                                              gets the binary built on the host (this machine
                                              cannot pull the Rust image) and a `curl` is
                                              retried until the server answers
    python3 .ci/readme_podman.py check        the blocks' options equal docker-compose.yml's

`check` compares, per compose service, the security options (podman's `unmask=ALL` is
Docker's `systempaths=unconfined`), the memory and process limits and the stop grace
period with those of the README's `podman run` for it: `mazearena` (the single server),
`api1` (the API server) and `worker`.
"""
import re
import shlex
import sys

README = "README.md"
COMPOSE = "docker-compose.yml"


def blocks():
    lines = open(README).read().splitlines()
    start = lines.index("#### With podman")
    out, block = [], None
    for line in lines[start + 1:]:
        if block is not None:
            if line.startswith("```"):
                out.append(block)
                block = None
            else:
                block.append(line)
        elif line.startswith("#"):
            break
        elif line == "```sh":
            block = []
    return out


def commands(block):
    out, acc = [], ""
    for line in block:
        if line.endswith("\\"):
            acc += (line[:-1].strip() if acc else line[:-1].rstrip()) + " "
            continue
        acc += line.strip() if acc else line
        out.append(acc)
        acc = ""
    return out


def compose_services():
    """service -> {key: value or list}, from the compose file's plain block style."""
    services, name, key = {}, None, None
    for line in open(COMPOSE).read().splitlines():
        if re.match(r"^[a-z]", line):
            name = None
            if line.startswith("services:"):
                name = ""
            continue
        if name is None:
            continue
        m = re.match(r"^  ([a-z0-9_-]+):", line)
        if m:
            name, key = m.group(1), None
            services[name] = {}
            continue
        m = re.match(r"^    ([a-z_]+):\s*(.*)$", line)
        if m and name:
            key, value = m.group(1), m.group(2).split(" #")[0].strip()
            services[name][key] = value if value else []
            continue
        m = re.match(r"^      - (.*)$", line)
        if m and name and key and isinstance(services[name].get(key), list):
            services[name][key].append(m.group(1).strip().strip('"'))
    return services


def podman_options(command):
    """The options of a `podman run` that the compose file also sets."""
    words = shlex.split(command)
    opts = {"security_opt": [], "mem_limit": None, "pids_limit": None, "stop_grace_period": None}
    for i, w in enumerate(words):
        nxt = words[i + 1] if i + 1 < len(words) else ""
        if w == "--security-opt":
            opts["security_opt"].append("systempaths=unconfined" if nxt == "unmask=ALL" else nxt)
        elif w == "--memory":
            opts["mem_limit"] = nxt
        elif w == "--pids-limit":
            opts["pids_limit"] = nxt
        elif w == "--stop-timeout":
            opts["stop_grace_period"] = nxt + "s"
    return opts


def check():
    services = compose_services()
    runs = [c for b in blocks() for c in commands(b) if "podman run" in c]
    wanted = {"mazearena": "--name mazearena ", "api1": "--name mazearena-api ",
              "worker": "--name mazearena-worker-"}
    problems = []
    for service, marker in wanted.items():
        run = next((c for c in runs if marker in c), None)
        if run is None:
            problems.append(f"no `podman run {marker}...` in the README for compose's {service}")
            continue
        have = podman_options(run)
        want = services.get(service, {})
        for key in ("security_opt", "mem_limit", "pids_limit", "stop_grace_period"):
            w = want.get(key)
            w = sorted(w) if isinstance(w, list) else w
            h = sorted(have[key]) if key == "security_opt" else have[key]
            if key == "security_opt" and w is None:
                w = []
            if h != w:
                problems.append(f"{service}: compose has {key} {w!r}, the README's podman run {h!r}")
        print(f"{service}: {have}")
    if problems:
        sys.exit("the README's podman examples differ from docker-compose.yml:\n  " + "\n  ".join(problems))


if __name__ == "__main__":
    if sys.argv[1:2] == ["check"]:
        check()
    elif sys.argv[1:2] == ["script"]:
        for line in blocks()[int(sys.argv[2])]:
            if line.startswith("podman build "):
                line = line.replace("podman build ", 'podman build --build-arg BINARY=prebuilt --build-arg PREBUILT="$BIN" ', 1)
            elif line.startswith("curl "):
                line = "answer_of " + line
            print(line)
    elif sys.argv[1:2] == ["commands"]:
        for command in commands(blocks()[int(sys.argv[2])]):
            print(command)
    else:
        sys.exit(__doc__)
