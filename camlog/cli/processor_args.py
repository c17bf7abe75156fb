"""Command-line flags generated from processor declarations, and errors worded with them.

A processor with a flag is chosen by ``--{name}`` (taking its primary option's value, e.g.
``--rectify OST.YAML``); its other options are flags of their own (``--low``). A processor
without a flag (throttle) is chosen by giving any of its options.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

from processors.errors import OptionValueError
from processors.spec import Configured, Option, ProcessorSpec

from ..errors import UsageError
from ..processing.options import configure_values

__all__ = ["add_processor_arguments", "chosen_processors", "flag_of", "worded"]


def _dest(spec: ProcessorSpec, option: Option | None = None) -> str:
    return f"{spec.name}__{option.name if option is not None else 'chosen'}"


def flag_of(spec: ProcessorSpec, option: str) -> str:
    """The command-line flag of one of ``spec``'s options."""
    return spec.cli_flag if option == spec.primary else spec.option(option).cli_flag


def _help(option: Option) -> str:
    default = "" if option.default is None else f" (default {option.default:g})" \
        if isinstance(option.default, int | float) else f" (default {option.default})"
    return option.help + default


def _outputs(spec: ProcessorSpec) -> str:
    if not spec.outputs:
        return ""
    return " -> " + "; ".join(f"NS/{o.name} ({o.msgtype.rpartition('/')[2]}: {o.help or o.label})"
                              for o in spec.outputs)


def add_processor_arguments(p: argparse.ArgumentParser, specs: Sequence[ProcessorSpec], *,
                            required: bool = False) -> None:
    """One argument group per processor; ``required``: one of the exclusive options of a
    flagless processor must be given (``camlog throttle``)."""
    for spec in specs:
        group = p.add_argument_group(spec.title or spec.name)
        if spec.flag:
            if spec.primary:
                primary = spec.option(spec.primary)
                group.add_argument(spec.cli_flag, dest=_dest(spec), metavar=primary.metavar or
                                   "VALUE", help=f"{spec.summary}{_outputs(spec)}")
            else:
                group.add_argument(spec.cli_flag, dest=_dest(spec), action="store_true",
                                   help=f"{spec.summary}{_outputs(spec)}")
        elif not spec.outputs:
            group.description = spec.summary
        exclusive = group.add_mutually_exclusive_group(required=required) \
            if spec.exclusive else None
        for option in spec.options:
            if option.name == spec.primary:
                continue
            where = exclusive if exclusive is not None and option.name in spec.exclusive \
                else group
            where.add_argument(option.cli_flag, dest=_dest(spec, option),
                               metavar=option.metavar or option.name.upper(),
                               help=_help(option))


@contextmanager
def worded(spec_flags: dict[str, ProcessorSpec]) -> Iterator[None]:
    """Reword :class:`OptionValueError` with the flags of the options at fault."""
    try:
        yield
    except OptionValueError as err:
        spec = spec_flags.get(err.processor)
        if spec is None:
            raise
        flags = "/".join(flag_of(spec, name) if any(o.name == name for o in spec.options)
                         else name for name in err.options) or spec.cli_flag
        raise UsageError(f"{flags}: {err.problem}") from None


def chosen_processors(args: argparse.Namespace,
                      specs: Sequence[ProcessorSpec]) -> list[Configured]:
    """The processors the command line chose, configured, in declaration order."""
    chosen = []
    with worded({spec.name: spec for spec in specs}):
        for spec in specs:
            values = {o.name: getattr(args, _dest(spec, o), None) for o in spec.options
                      if o.name != spec.primary}
            given = [name for name, value in values.items() if value is not None]
            if spec.flag:
                flag = getattr(args, _dest(spec))
                if spec.primary:
                    values[spec.primary] = flag
                if not flag:
                    if given:
                        raise UsageError(f"{flag_of(spec, given[0])} needs {spec.cli_flag}")
                    continue
            elif not given:
                continue
            chosen.append(configure_values(spec, values))
    return chosen
