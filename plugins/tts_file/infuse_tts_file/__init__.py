"""Recorded speech for infuse (TTS engine ``file``): a WAV plus a phoneme timing file.

:mod:`.timing` reads timing files (Praat TextGrid as written by the Montreal Forced Aligner,
MFA's JSON, infuse's own JSON, TSV/CSV and HTK label files) into labelled intervals,
:mod:`.audio` reads the WAV, :mod:`.engine` validates both and builds the
:class:`~infuse.speech.Utterance`.
"""
