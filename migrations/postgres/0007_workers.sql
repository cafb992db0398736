-- mazearena schema, version 7 (PostgreSQL): as the SQLite migration of the same number.

create table worker (
    worker_id text primary key,
    role text not null,
    host text not null,
    pid bigint not null,
    jobs bigint not null,
    sandbox text not null,
    matches_done bigint not null default 0,
    started_at bigint not null,
    last_seen bigint not null,
    stopped_at bigint
);

create index worker_last_seen on worker (last_seen);
