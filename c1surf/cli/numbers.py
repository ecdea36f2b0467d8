"""Click parameter types for numbers that refuse NaN and infinity, and one-line usage errors.

``click.FloatRange`` lets ``nan`` through every range (each comparison with NaN is false),
and ``float`` takes ``nan`` and ``inf``: a NaN blend ratio then turns every output point
into NaN. ``FiniteFloat`` is the type of every float option of every command.
"""
from __future__ import annotations

import math

import click


def _number(value: float) -> str:
    """``value`` as the user would type it: 0.5, 1, 1e-06."""
    return f"{value:g}"


class FiniteFloat(click.FloatRange):
    """A finite float, optionally within [min, max] (open ends with ``min_open``/``max_open``).

    Errors name the range the way the help does: ``2 is not in [0, 1]``, ``nan is not a finite number``.
    """

    name = "float"

    def __init__(self, min: float | None = None, max: float | None = None,
                 min_open: bool = False, max_open: bool = False):
        super().__init__(min=min, max=max, min_open=min_open, max_open=max_open, clamp=False)

    def convert(self, value, param, ctx):
        number = click.types.FloatParamType.convert(self, value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value} is not a finite number", param, ctx)
        low = self.min is not None and (number <= self.min if self.min_open else number < self.min)
        high = self.max is not None and (number >= self.max if self.max_open else number > self.max)
        if low or high:
            self.fail(f"{value} is not in {self.describe()}", param, ctx)
        return number

    def describe(self) -> str:
        """The range as an interval: [0, 1], (0, 180), [0, inf)."""
        left = "(" if self.min_open or self.min is None else "["
        right = ")" if self.max_open or self.max is None else "]"
        low = "-inf" if self.min is None else _number(self.min)
        high = "inf" if self.max is None else _number(self.max)
        return f"{left}{low}, {high}{right}"

    def _describe_range(self) -> str:  # the help's "[0<=x<=1]"
        return self.describe() if (self.min is not None or self.max is not None) else "finite"

    def __repr__(self) -> str:
        return f"FiniteFloat{self.describe()}"


def usage_line(error: click.UsageError) -> str:
    """One line for a click usage error: ``--blend: 2 is not in [0, 1]``, ``no such option: --blned``.

    Names the command's --help for what the line cannot say.
    """
    if isinstance(error, click.BadParameter):
        hint = error.param_hint
        if hint is None and error.param is not None:
            hint = _param_name(error.param)
        if isinstance(error, click.MissingParameter):
            what = error.param_type or (error.param.param_type_name if error.param is not None else "parameter")
            text = f"missing {what} {hint}" if hint else f"missing {what}"
            if error.message:
                text += f": {error.message}"
        else:
            text = f"{_join(hint)}: {error.message}" if hint else error.message
    else:
        text = error.format_message()
    text = " ".join(str(text).split()).replace(". (", " (").rstrip(".")
    text = text[:1].lower() + text[1:] if text[:2] != text[:2].upper() else text
    command = error.ctx.command_path if error.ctx is not None else "c1surf"
    return f"{text} (see `{command} --help`)"


def _param_name(param) -> str:
    """The option's longest name (``--blend``) or the argument's metavar (``INPUT``)."""
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    return param.metavar or (param.name or "").upper()


def _join(hint) -> str:
    if isinstance(hint, (list, tuple)):
        return " / ".join(str(h) for h in hint)
    return str(hint).strip("'\"")


class OneLineUsageError(click.UsageError):
    """A usage error printed as one ``c1surf: error:`` line, exit status 2."""

    def show(self, file=None):
        click.echo(f"c1surf: error: {self.message}", err=True)
