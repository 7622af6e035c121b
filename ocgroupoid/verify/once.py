"""What the checks build once per transcription: replays, residual and sensitivity maps."""

from __future__ import annotations

import functools
from typing import Callable, TypeVar
from weakref import WeakKeyDictionary

from ..nlp.transcription import Transcription

Built = TypeVar("Built")


def per_transcription(build: Callable[[Transcription], Built]
                      ) -> Callable[[Transcription], Built]:
    """``build(tr)`` made once per transcription and kept while it lives (weakly keyed: what
    is built must not refer to the transcription itself, or it would never be freed)."""
    made: WeakKeyDictionary[Transcription, Built] = WeakKeyDictionary()

    @functools.wraps(build)
    def once(tr: Transcription) -> Built:
        if tr not in made:
            made[tr] = build(tr)
        return made[tr]

    return once
