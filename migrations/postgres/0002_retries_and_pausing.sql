-- mazearena schema, version 2 (PostgreSQL): as the SQLite migration of the same number.

alter table match add column lease_expiries bigint not null default 0;

alter table bot add column paused_reason text;
alter table bot add column paused_at bigint;
alter table bot add column resumed_at bigint;
