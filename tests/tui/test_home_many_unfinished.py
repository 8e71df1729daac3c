"""A home screen over hundreds of unfinished sessions keeps New session in reach (issue 27,
finding 8): the newest few are offered, the rest summed up in one line that lists them."""

from __future__ import annotations

import shutil

from station.tui.app import StationApp, StationConfig
from station.tui.screens.home import RESUME_OFFERED
from tests.session.conftest import write_session


async def test_two_hundred_unfinished_sessions_leave_new_session_in_reach(tmp_path):
    folder = tmp_path / "sessions"
    first = write_session(folder, finish=False)
    for number in range(1, 200):
        shutil.copyfile(first, folder / f"{first.stem}-copy{number}.jsonl")
    app = StationApp(StationConfig(sessions_dir=folder, sessions_reason="test folder"))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.pause()
        choices = app.screen.query_one("#home-choices")
        prompts = [str(choices.get_option_at_index(i).prompt) for i in range(choices.option_count)]
        assert sum(p.startswith("Resume:") for p in prompts) == RESUME_OFFERED
        more = prompts[RESUME_OFFERED]
        assert f"{200 - RESUME_OFFERED} older unfinished sessions" in more
        assert prompts[RESUME_OFFERED + 1].startswith("New session")
        # Enter on the summing-up line lists every one of them, still before New session.
        choices.highlighted = RESUME_OFFERED
        await pilot.press("enter")
        await pilot.pause()
        prompts = [str(choices.get_option_at_index(i).prompt) for i in range(choices.option_count)]
        assert sum(p.startswith("Resume:") for p in prompts) == 200
        assert prompts[200].startswith("New session")
