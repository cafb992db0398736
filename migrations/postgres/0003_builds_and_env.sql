-- mazearena schema, version 3 (PostgreSQL): as the SQLite migration of the same number.

alter table bot_version add column build_command text;
alter table bot_version add column build_status text not null default 'ready';
alter table bot_version add column build_log text;
alter table bot_version add column built_at bigint;
alter table bot_version add column env text not null default '{}';

create index bot_version_build on bot_version (build_status);
