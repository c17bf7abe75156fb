"""One typed, validated request per command (frozen dataclasses): each option is declared once,
with what the command line needs (flags, help, type) and what a pipeline step needs (its
key, the field's name). The command line (:mod:`.arguments`), batch pipeline steps
(:mod:`.table`) and golden jobs all build their requests from these declarations; the flows
take the request."""
