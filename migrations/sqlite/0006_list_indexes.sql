-- mazearena schema, version 6: match lists that cost the same at a million matches as
-- at a thousand. Never edit an applied migration: add a new file.
--
-- A list is newest first (by match id) and filtered by at most a bot, a tournament, a
-- maze and a status; each filter gets an index whose order within one value is the
-- match id's, so a page reads its rows straight from the index, however many matches
-- the table holds. A bot's matches span its versions, so the match row also keeps the
-- bot (it never changes for a version); a trigger fills it for every writer.

alter table match add column bot_id integer references bot (bot_id);

update match set bot_id = (
    select v.bot_id from bot_version v where v.bot_version_id = match.bot_version_id
);

create trigger match_bot_id after insert on match
when new.bot_id is null
begin
    update match set bot_id = (
        select v.bot_id from bot_version v where v.bot_version_id = new.bot_version_id
    ) where match_id = new.match_id;
end;

create index match_bot on match (bot_id);
create index match_maze on match (maze_id);
create index match_status on match (status);
