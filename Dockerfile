# mazearena server image: the release binary, bubblewrap (every bot runs in its sandbox),
# plus Python 3 with numpy, pandas and scipy (what published robot.py solutions import)
# and Node.js so that uploaded bots and the starter bots can run, and gcc, g++ and make so
# that C and C++ sources uploaded with a `build` command can be built (add a Rust
# toolchain, golang-go or a JDK here to build those on the server). GET /api/runtimes
# lists what the image offers bots.

# Where the binary comes from: `build` (default) compiles it in the Rust image;
# `--build-arg BINARY=prebuilt` takes target/release/mazearena from the build context
# instead (built on a bookworm-compatible host: for machines that cannot pull the Rust
# image). The runtime stage below is the same either way.
ARG BINARY=build

FROM rust:1-bookworm AS build
WORKDIR /src
COPY Cargo.toml Cargo.lock build.rs ./
COPY src src
COPY migrations migrations
COPY mazes mazes
RUN cargo build --release --locked && cp target/release/mazearena /mazearena

FROM scratch AS prebuilt
ARG PREBUILT=target/release/mazearena
COPY ${PREBUILT} /mazearena

FROM ${BINARY} AS binary

FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends python3 python3-numpy python3-pandas python3-scipy nodejs tini ca-certificates bubblewrap gcc g++ make libc6-dev \
    && rm -rf /var/lib/apt/lists/* \
    && groupadd --system --gid 999 mazearena \
    && useradd --system --uid 999 --gid 999 --create-home --home-dir /var/lib/mazearena mazearena \
    && mkdir -p /var/lib/mazearena/db /var/lib/mazearena/bots \
    && chown -R mazearena:mazearena /var/lib/mazearena
COPY --from=binary /mazearena /usr/local/bin/mazearena
COPY bots /opt/mazearena/bots
COPY mazes /opt/mazearena/mazes
# A fixed uid and gid (999): Kubernetes' runAsUser and runAsNonRoot name it
# (deploy/kubernetes/), and volumes made by an earlier image keep their owner.
USER 999:999
WORKDIR /var/lib/mazearena
ENV MAZEARENA_BIND=0.0.0.0:8080 \
    MAZEARENA_DATABASE=sqlite:///var/lib/mazearena/db/mazearena.db \
    MAZEARENA_DATA_DIR=/var/lib/mazearena/bots
VOLUME ["/var/lib/mazearena/db", "/var/lib/mazearena/bots"]
EXPOSE 8080
# The server's own port (MAZEARENA_BIND); a `worker` serves no HTTP: run it with the
# health check off (compose: `healthcheck: disable`, podman: `--no-healthcheck`).
HEALTHCHECK --interval=30s --timeout=5s \
    CMD python3 -c "import os, urllib.request; port = os.environ['MAZEARENA_BIND'].rsplit(':', 1)[1]; urllib.request.urlopen('http://127.0.0.1:' + port + '/healthz', timeout=4)"
# tini passes SIGTERM on, so running matches finish or are re-queued on `docker stop`.
ENTRYPOINT ["tini", "--", "mazearena"]
CMD ["serve"]
