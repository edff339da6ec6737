"""espeak-ng text-to-speech for infuse (engine ``espeak``, the default).

:mod:`.library` binds libespeak-ng through ctypes and synthesizes with phoneme, word, sentence and
mark events; :mod:`.timeline` turns those events into phoneme, word and mark times;
:mod:`.pyttsx3_writer` has pyttsx3 (driver ``espeak``) write the WAV in a child process and
:mod:`.isolated` runs the timing synthesis in another; :mod:`.engine` ties them together and checks
that the WAV equals the audio the timings belong to.

Nothing is imported here: the child processes start from this package and must start fast.
"""
