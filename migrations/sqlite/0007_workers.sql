-- mazearena schema, version 7: the processes that play matches report themselves, so
-- that the servers' health, metrics and pages can show every worker, on any machine.
-- Never edit an applied migration: add a new file.

create table worker (
    -- the worker's lease owner name (unique per process start)
    worker_id text primary key,
    -- `serve` (a server with match workers) or `worker` (`mazearena worker`)
    role text not null,
    host text not null,
    pid integer not null,
    -- how many matches it plays at once (its cores in use)
    jobs integer not null,
    -- the sandbox level its bots run at (full, none)
    sandbox text not null,
    -- matches it has recorded since it started
    matches_done integer not null default 0,
    started_at integer not null,
    -- its last report (unix ms): a worker not seen for a few lease periods is gone
    last_seen integer not null,
    -- set when it stopped gracefully
    stopped_at integer
);

create index worker_last_seen on worker (last_seen);
