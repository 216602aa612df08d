"""The plugin pages: one per registered plugin, generated from its module.

A page is the module's docstring (its ``.. parameters::`` line replaced by the
table made from ``PARAMS`` and the options), then what follows from the
declarations: the XML example as a Python dictionary, notes, the renders that
vary its main parameter (:mod:`docs_previews`), the related Mitsuba plugins,
its lobe plot (from the committed validation report) and its bundled scene.
"""
from __future__ import annotations

import inspect
import math
import os
import re
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import docs_previews

DOCS = Path(__file__).resolve().parent.parent
ROOT = DOCS.parent
PARAMETERS = ".. parameters::"     # the line of a model's docstring that becomes its table
FORMS = {"spectrum": "float, rgb, spectrum or texture", "scalar": "float or texture",
         "float": "float"}
MITSUBA_DOCS = "https://mitsuba.readthedocs.io/en/stable/src/generated/plugins_bsdfs.html"


# ----------------------------------------------------------------------------
#  The parameter table, from the declarations
# ----------------------------------------------------------------------------

SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
SCIENTIFIC = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?)e([+-]?\d+)(?![\w.])")
NUMBER = r"-?\d+(?:\.\d+)?(?:e[+-]?\d+)?"
CONSTANT = r"``(?:\w+\.)*([A-Z][A-Z0-9]*_[A-Z0-9_]*[A-Z0-9])``"


def number(value: float) -> str:
    """A number as a reader writes it: 10⁶ for 1e6, 5.1 × 10⁻⁶, π/2, 0.3."""
    if abs(value - math.pi / 2) < 1e-12:
        return "π/2"
    if value > 0 and abs(round(math.log10(value))) >= 4 and \
            math.isclose(value, 10.0 ** round(math.log10(value)), rel_tol=1e-12):
        return "10" + str(round(math.log10(value))).translate(SUPERSCRIPT)
    text = f"{value:g}"
    return SCIENTIFIC.sub(_power, text) if "e" in text else text


def _power(match: re.Match) -> str:
    mantissa, exponent = match.group(1), str(int(match.group(2))).translate(SUPERSCRIPT)
    return f"10{exponent}" if mantissa == "1" else f"{mantissa} × 10{exponent}"


def human(text: str, constants: dict[str, float] = {}) -> str:   # noqa: B006 (read only)
    """A declaration's or a docstring's prose for the page: the code's
    constant names (``ALPHA_MIN`` = 1e-4, ``phong.MAX_EXPONENT``) give way to
    their values, and numbers in e-notation read 10⁻⁴ (code literals and
    blocks are left as they are)."""
    return _powers(unname(text, constants))


def _powers(prose: str) -> str:
    parts = re.split(r"(``.*?``)", prose)                         # outside literals only
    return "".join(p if p.startswith("``") else SCIENTIFIC.sub(_power, p) for p in parts)


def human_docstring(doc: str, constants: dict[str, float]) -> str:
    """:func:`human` for a module docstring (reStructuredText): its prose
    lines only, never a directive's or a literal block's content."""
    lines, block = [], None             # block: the indent a block's content exceeds
    for line in unname(doc, constants).splitlines():
        indent = len(line) - len(line.lstrip())
        if block is not None and (not line.strip() or indent > block):
            lines.append(line)
            continue
        block = None
        lines.append(_powers(line))
        if line.rstrip().endswith("::") or line.lstrip().startswith(".. "):
            block = indent
    return "\n".join(lines)


def unname(text: str, constants: dict[str, float]) -> str:
    """The code's constant names in ``text`` replaced by their values."""
    text = re.sub(rf"{CONSTANT} = ({NUMBER})", lambda m: number(float(m.group(2))), text)
    text = re.sub(rf"{CONSTANT} = ", "", text)                   # "= π/2 - 1e-6" follows
    return re.sub(CONSTANT, lambda m: number(constants[m.group(1)]) if m.group(1) in constants
                  else m.group(0), text)


def constants_of(cls) -> dict[str, float]:
    """The numeric module-level constants a plugin's text may name."""
    from mi_brdfs.bsdfs import microfacet, params
    found = {}
    for module in (params, microfacet, inspect.getmodule(cls)):
        found.update({k: float(v) for k, v in vars(module).items()
                      if k.isupper() and isinstance(v, (int, float)) and not isinstance(v, bool)})
    return found


def _range(lo, hi) -> str:
    if lo is not None and hi is not None:
        return f" in [{number(lo)}, {number(hi)}]"
    if lo is not None:
        return f" ≥ {number(lo)}"
    return f" ≤ {number(hi)}" if hi is not None else ""


def _row(name: str, kind: str, doc: str, default: str, constants: dict[str, float]) -> list[str]:
    lines = textwrap.wrap(human(" ".join(doc.split()), constants), 66) or [""]
    return [f"   * - ``{name}``", f"     - {kind}", f"     - {lines[0]}",
            *(f"       {line}" for line in lines[1:]), f"     - {default}"]


FLAG_LEGEND = ("Flags: **P** exposed by ``mi.traverse`` (``params.update()`` changes it), "
               "**∂** differentiable, **D** discontinuous (the sampler moves with it); "
               "options (no flag) are fixed at load time.")


def flags(cls, p) -> str:
    """A parameter's flags as Mitsuba's plugin pages print them (P, ∂, D),
    read from the flags the plugin's ``traverse`` puts it with (every
    declared parameter it reads is put, so exposed)."""
    import mitsuba as mi
    f = cls.traverse_flags(p)         # Differentiable is 0: the absence of NonDifferentiable
    return " ".join(["P"] + ([] if f & mi.ParamFlags.NonDifferentiable else ["∂"])
                    + (["D"] if f & mi.ParamFlags.Discontinuous else []))


def parameter_table(cls) -> str:
    """The reStructuredText table of a plugin's parameters and options, made
    from its declarations (``PARAMS``, the model's ``OPTIONS``, then the
    base's): the one source of the plugin's parameter documentation. Its
    flags column and the legend under it are Mitsuba's (:func:`flags`)."""
    rows = [".. list-table::", "   :header-rows: 1", "   :widths: 18 18 46 10 8", "",
            "   * - Parameter", "     - Type", "     - Description", "     - Default",
            "     - Flags"]
    constants = constants_of(cls)
    for p in cls.PARAMS:
        kind = FORMS[p.kind] + _range(p.lo, p.hi)
        rows += _row(p.name, kind, p.doc, "none" if p.optional else number(p.default),
                     constants) + [f"     - {flags(cls, p)}"]
    for o in cls.OPTIONS + tuple(o for o in cls.all_options() if o not in cls.OPTIONS):
        doc = o.doc
        if isinstance(o.default, bool):
            kind, default = "boolean", str(o.default).lower()
        elif isinstance(o.default, int):
            kind, default = "integer" + _range(o.lo, o.hi), str(o.default)
        else:
            kind, default = "string", f'``"{o.default}"``'
            doc += " One of " + ", ".join(f'``"{c}"``' for c in o.choices) + "."
        rows += _row(o.name, kind, doc, default, constants) + ["     -"]
    return "\n".join(rows + ["", FLAG_LEGEND])


# ----------------------------------------------------------------------------
#  The Python example, from the XML example
# ----------------------------------------------------------------------------

def xml_example(doc: str) -> str:
    """The first ``<bsdf>`` element of the docstring's first XML code block."""
    block = doc.split(".. code-block:: xml", 1)[1]
    lines = []
    for line in block.splitlines()[1:]:
        if line.strip() and not line.startswith(" "):
            break
        lines.append(line)
    text = textwrap.dedent("\n".join(lines))
    return text[:text.index("</bsdf>") + len("</bsdf>")].strip()


def _number(text: str):
    value = float(text)
    return int(value) if value.is_integer() and "." not in text and "e" not in text else value


def plugin_dict(element: ET.Element) -> dict:
    """A Mitsuba XML plugin element as the dictionary ``mi.load_dict`` reads:
    ``float``, ``integer``, ``boolean``, ``string``, ``rgb`` and nested plugins
    (textures) by name."""
    d = {"type": element.get("type")}
    for child in element:
        name, value = child.get("name"), child.get("value")
        if child.tag == "float":
            d[name] = float(value)
        elif child.tag == "integer":
            d[name] = int(value)
        elif child.tag == "boolean":
            d[name] = value.strip().lower() == "true"
        elif child.tag == "string":
            d[name] = value
        elif child.tag == "rgb":
            d[name] = {"type": "rgb", "value": [float(v) for v in value.replace(",", " ").split()]}
        elif child.tag in ("texture", "bsdf"):
            d[name] = plugin_dict(child)
        else:
            raise ValueError(f"the XML example's <{child.tag}> has no dictionary form here")
    return d


def _source(value, indent: int) -> str:
    if isinstance(value, dict):
        pad = " " * (indent + 4)
        items = [f"{pad}{k!r}: {_source(v, indent + 4)}," for k, v in value.items()]
        return "{\n" + "\n".join(items) + "\n" + " " * indent + "}"
    return repr(value)


def python_example(xml: str) -> str:
    """Python code that loads the XML example's BSDF as a dictionary."""
    d = plugin_dict(ET.fromstring(xml))
    return ("import mi_brdfs          # first: sets up LLVM, registers the plugins\n"
            "import mitsuba as mi\n\n"
            f"bsdf = mi.load_dict({_source(d, 0)})\n").replace("'", '"')


# ----------------------------------------------------------------------------
#  The page
# ----------------------------------------------------------------------------

def _image(path: Path, srcdir: Path, alt: str, width: str | None = None) -> list[str]:
    """An image directive for a file anywhere (relative to the source folder)."""
    lines = [f".. image:: /{os.path.relpath(path, srcdir)}", f"   :alt: {alt}"]
    return lines + ([f"   :width: {width}"] if width else [])


def notes(cls, pictures) -> list[str]:
    from mi_brdfs.bsdfs.base import MODE
    lines = ["Notes", "-----", "",
             "- **Modes** (``mode``): " + " ".join(MODE.doc.split()),
             "- **One-sided**, as Mitsuba's own reflection models: a viewer below the "
             "surface (behind its shading normal) gets no reflection. Wrap the plugin in "
             "Mitsuba's ``twosided`` for a surface seen from both sides.",
             "- **Variants**: the plugin loads in every variant of the Mitsuba wheel "
             "(``mi_brdfs.register()`` after ``mi.set_variant(...)``); in the polarized "
             "variants it is a depolarizer, as Mitsuba's ``diffuse``.",
             "- **Differentiable**: every parameter marked ∂ is exposed by ``mi.traverse`` "
             "and can be updated and differentiated; options are fixed at load time."]
    varied = [s.parameter for s in pictures if any(p.name == s.parameter for p in cls.PARAMS)]
    if varied:                          # what they mean is the table's: not repeated here
        lines.append("- **Renders**: " + " and ".join(f"``{v}``" for v in varied)
                     + " vary in the renders below (see the table for what each means).")
    return lines + [""]


def renders_section(cls, work: Path, srcdir: Path) -> list[str]:
    from mi_brdfs.bsdfs.cases import ALL
    sweeps = ALL[cls.name].picture_sets()
    if not sweeps:
        return []
    lines = ["Renders", "-------", ""]
    for sweep in sweeps:
        lines += sweep_table(cls, sweep, work, srcdir)
    if cls.name == "cook_torrance":
        lines += gold_section(work, srcdir)
    return lines


MODE_NAMES = {"scanline": "scan-line mode", "hdr": "hdr mode"}


def figure(path: Path, srcdir: Path, alt: str, caption: str) -> list[str]:
    """A captioned figure of a render grid (:func:`grid`)."""
    return [*(_image(path, srcdir, alt)), "", f"   {caption}", ""]


def grid(figures: list[list[str]]) -> list[str]:
    """Figures side by side, as many as the column holds (``matpreview`` in the
    site's style sheet): Mitsuba's plugin pages show their renders so."""
    lines = [".. container:: matpreview", ""]
    for f in figures:
        lines += ["   .. figure::" + f[0][len(".. image::"):],
                  *("   " + x if x else x for x in f[1:])]
    return lines


def sweep_table(cls, pictures, work: Path, srcdir: Path) -> list[str]:
    """One sweep's renders: its caption, then a captioned grid per mode."""
    from mi_brdfs.bsdfs.cases import label
    made = docs_previews.renders(cls, work / "previews", pictures)
    values = list(pictures.values)
    rest = label(pictures.config) if pictures.config else "defaults"
    lines = [f"``{pictures.parameter}`` from {values[0]:g} to {values[-1]:g}, the other "
             f"parameters: {rest}: {docs_previews.SCENE}, {docs_previews.RES}² pixels.", ""]
    for mode in ("hdr", "scanline"):
        lines += [f"**{MODE_NAMES[mode].capitalize()}**: {docs_previews.LIGHTS[mode]}.", ""]
        lines += grid([figure(r.path, srcdir, f"{cls.name}, {mode}, {pictures.parameter} = "
                              f"{r.value:g}", f"``{pictures.parameter}`` = {r.value:g}, "
                              f"{MODE_NAMES[mode]}")
                       for r in made if r.mode == mode])
    return lines


def gold_section(work: Path, srcdir: Path) -> list[str]:
    """cook_torrance: gold under Schlick's F (the lecture's), F82-tint and the
    exact conductor's, side by side, with how their parameters were made."""
    g = docs_previews.gold()
    made = docs_previews.gold_renders(work / "previews")
    triple = lambda v: "(" + ", ".join(f"{x:.3f}" for x in v) + ")"      # noqa: E731
    raised = [c for c, r in zip("RGB", g.raised) if r]
    captions = {
        "schlick": f'``fresnel="schlick"`` (the lecture\'s): ``f0`` = {g.f0:.3f}, '
                   f"``specular_reflectance`` = {triple(g.colour)}",
        "f82": f'``fresnel="f82"``: the same, ``f82_tint`` = {triple(g.tint)}',
        "conductor": '``fresnel="conductor"``, ``material="Au"``'}
    text = [
        "Gold, three Fresnel forms", "^^^^^^^^^^^^^^^^^^^^^^^^^", "",
        f"The same gold sphere (GGX, Smith G, α = {docs_previews.GOLD_ROUGHNESS['alpha']:g}, "
        f"``k`` = 0, hdr mode) under the lecture's Schlick F, Hoffman's F82-tint and the "
        f"exact conductor's F with Mitsuba's ``Au`` data. The parameters of the first two "
        f"are computed by this site's build from the exact conductor Fresnel of gold's "
        f"index (the RGB colour ``roughconductor`` makes of Mitsuba's ``Au`` data): "
        f"F(0°) = {triple(g.normal)} and F(81.8°) = {triple(g.f82)} (81.8° = acos 1/7, "
        f"where F82-tint sets its value). ``f0`` is one number here, so, as a user would, "
        f"``f0`` is the largest channel of F(0°) and ``specular_reflectance`` the rest "
        f"(their product is F(0°)); ``f82_tint`` is F(81.8°) over that Schlick curve "
        f"there" + (f", held at 1 in {' and '.join(raised)}: gold reflects more there than "
                   f"Schlick's curve of one ``f0``, and F82-tint can only lower it"
                   if raised else "") + ". Schlick's colour stays gold's at grazing "
        f"angles; the exact conductor's turns paler.", ""]
    return text + grid([figure(r.path, srcdir, f"cook_torrance, gold, fresnel = {r.label}",
                               captions[r.label]) for r in made])


def mitsuba_section(cls) -> list[str]:
    from mi_brdfs.bsdfs.cases import ALL
    related = ALL[cls.name].mitsuba
    if not related:
        return []
    links = ", ".join(f"`{name} <{MITSUBA_DOCS}#bsdf-{name}>`__" for name in related)
    return ["Related Mitsuba plugins", "-----------------------", "",
            f"In Mitsuba's plugin reference: {links}.", ""]


def page(cls, work: Path, srcdir: Path) -> str:
    from mi_brdfs.bsdfs.cases import ALL
    module = inspect.getmodule(cls)
    name = cls.name
    doc = inspect.getdoc(module).strip()
    body = human_docstring(doc, constants_of(cls)).replace(PARAMETERS, parameter_table(cls))
    parts = [f".. _plugin-{name}:", "", body, "",
             "The same BSDF from Python, as a dictionary:", "",
             ".. code-block:: python", "",
             textwrap.indent(python_example(xml_example(doc)), "    "), ""]
    parts += notes(cls, ALL[name].picture_sets())
    parts += renders_section(cls, work, srcdir)
    parts += mitsuba_section(cls)
    lobe = DOCS / "validation" / f"lobe_{name}.png"
    if lobe.exists():
        parts += ["Lobes", "-----", "",
                  "Polar plots of ``eval`` in the plane of incidence (from the "
                  ":doc:`validation report </results/validation>`): the radius is "
                  r":math:`f\cos\theta_o`, per steradian in hdr mode and the lecture's "
                  "value (no unit) in scan-line mode, both plots on one radial scale, one "
                  r"curve per viewer's angle :math:`\theta_i`:", "",
                  *_image(lobe, srcdir, f"{name} lobes"), ""]
    scene = ROOT / "scenes" / f"{name}.xml"
    if scene.exists():
        parts += ["Bundled scene", "-------------", "",
                  f"``mi-brdfs render {name}`` renders it; from Python, "
                  f"``mi.load_file(mi_brdfs.scenes.path(\"{name}\"))``. Scan-line mode "
                  f"(``-D mode=scanline``) on the left, hdr mode on the right:", ""]
        renders = [ROOT / "scenes" / "renders" / f"{name}_{mode}.png" for mode in ("scanline", "hdr")]
        if all(r.exists() for r in renders):
            parts += [".. list-table::", "   :class: renders", ""]
            for i, (r, mode) in enumerate(zip(renders, ("scanline", "hdr"))):
                image = _image(r, srcdir, f"{name}, {mode}")
                parts += [("   * - " if i == 0 else "     - ") + image[0],
                          *("       " + line for line in image[1:])]
            parts.append("")
        parts += [f".. literalinclude:: /{os.path.relpath(scene, srcdir)}",
                  "   :language: xml", ""]
    return "\n".join(parts)


def pages(work: Path, srcdir: Path) -> dict[str, tuple[str, str]]:
    """docname -> (suffix, text) of the plugin pages and their index."""
    from mi_brdfs.bsdfs import PLUGINS
    out = {f"plugins/{cls.name}": (".rst", page(cls, work, srcdir)) for cls in PLUGINS}
    index = ["BSDF plugins", "============", "",
             "One page per plugin, in the lecture's order (diffuse models, then glossy "
             "ones), generated from the plugin's module: its parameter declarations, its "
             "formulas and its examples; the renders are made by this site's build.", "",
             ".. toctree::", "   :maxdepth: 1", "", *(f"   {cls.name}" for cls in PLUGINS), ""]
    out["plugins/index"] = (".rst", "\n".join(index))
    return out

