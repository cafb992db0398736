-- mazearena schema, version 5 (PostgreSQL): a match's record stored compactly, apart
-- from the match row, as the SQLite migration of the same number.

create table match_record (
    match_id bigint primary key references match (match_id) on delete cascade,
    -- see src/storage/records.rs for the encodings
    encoding bigint not null,
    -- zstd-compressed
    data bytea not null
);

create index match_inline_trace on match (match_id) where trace is not null;
