"""Lip sync and facial expressions for infuse.

:mod:`.tables` loads the data (phoneme -> viseme -> channel tables, channel names, FACS and
lexemes); :mod:`.channels` finds the face channels a character offers; :mod:`.coarticulation`
blends phoneme targets over time; :mod:`.lipsync` turns an utterance into weight tracks for a
character; :mod:`.joints` drives joint faces; :mod:`.expressions` maps action units and lexemes;
:mod:`.command` is ``infuse speak``.
"""
