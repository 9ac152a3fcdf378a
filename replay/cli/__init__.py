"""The command line: ``main`` parses, ``commands/`` holds one module per verb (the verbs that front
``recorder/`` — record, annotate, filter, recover, synth, frame — among them).

May import anything of ours; nothing imports it.
"""
