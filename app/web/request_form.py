"""A request type's fields as a form shows them, read from its JSON schema: the type, the
default, the bounds and the help are the request's own, never written again here.

The page checks a field against these bounds before sending (the script reads them from
``data-`` attributes); the service checks the request again, and its errors name the same
fields, so the page marks the field the service names.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from touchbench.app.schemas.base import Request

#: How a list field is typed in: names separated by commas, or one entry a line (entries
#: that hold commas or spaces, such as WEKA command lines).
LINE_LISTS = frozenset({"weka"})


@dataclass(frozen=True)
class FormField:
    """One input of a request's form.

    Attributes
    ----------
    name : str
        The request's field name (the JSON key the page sends, the name errors use).
    kind : str
        ``integer``, ``number``, ``boolean``, ``choice``, ``text``, ``list`` or ``lines``.
    default : Any
        The request's default (``None``: absent).
    required : bool
    help : str
    choices : list of str
        The values of a ``choice``.
    bounds : dict of str to float
        ``minimum``, ``maximum``, ``exclusiveMinimum``, ``exclusiveMaximum``,
        ``minLength``, ``maxLength``, ``minItems``, ``maxItems`` as the schema gives them.
    nullable : bool
        Whether the field may be left empty (then the request's default applies).
    items : str
        ``number`` for a list of numbers (sent as numbers), else "".
    """

    name: str
    kind: str
    default: Any
    required: bool
    help: str
    choices: list[str] = field(default_factory=list)
    bounds: dict[str, float] = field(default_factory=dict)
    nullable: bool = False
    items: str = ""

    @property
    def label(self) -> str:
        return self.name.replace("_", " ")

    @property
    def shown_default(self) -> str:
        """The default as the input holds it ("" for none)."""
        if self.default is None:
            return ""
        if self.kind in ("list", "lines"):
            return ", ".join(str(item) for item in self.default) if self.kind == "list" else ""
        if isinstance(self.default, float) and self.default.is_integer():
            return str(int(self.default))
        return str(self.default)


@dataclass(frozen=True)
class FieldGroup:
    title: str
    fields: list[FormField]


_BOUNDS = (
    "minimum",
    "maximum",
    "exclusiveMinimum",
    "exclusiveMaximum",
    "minLength",
    "maxLength",
    "minItems",
    "maxItems",
)


def form_fields(kind: type[Request]) -> dict[str, FormField]:
    """Every field of ``kind``, in its order, as the form shows it."""
    schema = kind.model_json_schema()
    required = set(schema.get("required", ()))
    return {
        name: _field(name, spec, name in required)
        for name, spec in schema.get("properties", {}).items()
    }


def grouped(
    fields: Mapping[str, FormField], groups: Sequence[tuple[str, Sequence[str]]]
) -> list[FieldGroup]:
    """``fields`` in the named groups; those no group names in a last group, so that a field
    added to the request shows in the form."""
    placed = {name for _, names in groups for name in names}
    result = [
        FieldGroup(title, [fields[name] for name in names if name in fields])
        for title, names in groups
    ]
    rest = [f for name, f in fields.items() if name not in placed]
    if rest:
        result.append(FieldGroup("other", rest))
    return result


def _field(name: str, spec: dict[str, Any], required: bool) -> FormField:
    nullable = False
    body = spec
    if "anyOf" in spec:
        kinds = [option for option in spec["anyOf"] if option.get("type") != "null"]
        nullable = len(kinds) < len(spec["anyOf"])
        body = kinds[0] if len(kinds) == 1 else {"type": "string"}
    bounds = {key: body[key] for key in _BOUNDS if key in body}
    type_ = body.get("type")
    choices = [str(value) for value in body.get("enum", ())]
    if choices:
        kind = "choice"
    elif type_ == "array":
        kind = "lines" if name in LINE_LISTS else "list"
    elif type_ in ("integer", "number", "boolean"):
        kind = type_
    else:
        kind = "text"
    return FormField(
        name=name,
        kind=kind,
        default=spec.get("default"),
        required=required,
        help=str(spec.get("description", "")),
        choices=choices,
        bounds=bounds,
        nullable=nullable or not required,
        items="number" if body.get("items", {}).get("type") in ("number", "integer") else "",
    )
