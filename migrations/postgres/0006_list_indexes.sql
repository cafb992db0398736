-- mazearena schema, version 6 (PostgreSQL): match lists that cost the same at a million
-- matches as at a thousand, as the SQLite migration of the same number (each index ends
-- with the match id, which SQLite's indexes hold implicitly).

alter table match add column bot_id bigint references bot (bot_id);

update match set bot_id = v.bot_id from bot_version v
where v.bot_version_id = match.bot_version_id;

create function match_bot_id() returns trigger
language plpgsql as $$
begin
    if new.bot_id is null then
        select v.bot_id into new.bot_id from bot_version v
        where v.bot_version_id = new.bot_version_id;
    end if;
    return new;
end;
$$;

create trigger match_bot_id before insert on match
for each row execute function match_bot_id();

create index match_bot on match (bot_id, match_id);
create index match_maze on match (maze_id, match_id);
create index match_status on match (status, match_id);
