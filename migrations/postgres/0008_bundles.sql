-- mazearena schema, version 8 (PostgreSQL): as the SQLite migration of the same number.

create table bundle (
    sha256 text primary key,
    archive bytea not null,
    files bigint not null,
    bytes bigint not null,
    created_at bigint not null
);

alter table bot_version add column bundle_sha256 text references bundle (sha256);
alter table bot_version add column built_sha256 text references bundle (sha256);
alter table bot_version add column build_owner text;
alter table bot_version add column build_lease_expires_at bigint;
