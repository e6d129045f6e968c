"""SVG as real files write it: <use>, <symbol>, <defs>, <style> CSS, units, nested <svg>, <switch>, and hostile XML."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from skatetrace.drawings.curves import EllipticArcPiece, LinePiece
from skatetrace.drawings.svg import read_svg
from skatetrace.errors import DrawingError

MM = 96 / 25.4  # user units (CSS pixels) per millimetre


def svg(body: str, **root) -> str:
    attrs = " ".join(f'{k}="{v}"' for k, v in root.items())
    return f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" {attrs}>{body}</svg>'


def ends(drawing) -> dict:
    """Each path's start and end point, by name."""
    return {p.name: (p.pieces[0].start.tolist(), p.pieces[-1].end.tolist()) for p in drawing.paths}


# --- <use>, <symbol>, <defs> ----------------------------------------------------------------------------

@pytest.mark.parametrize("href", ['href="#s"', 'xlink:href="#s"'])
def test_a_symbol_in_defs_is_drawn_where_use_puts_it(href):
    drawing = read_svg(svg(f'<defs><symbol id="s"><path d="M 0 0 L 10 0 L 10 5"/></symbol></defs>'
                           f'<use {href} x="10" y="5"/>'))
    (path,) = drawing.paths
    assert path.name == "use-1" and [type(p) for p in path.pieces] == [LinePiece, LinePiece]
    np.testing.assert_allclose([p.start for p in path.pieces] + [path.pieces[-1].end],
                               [[10, -5], [20, -5], [20, -10]], atol=1e-12)


def test_a_symbol_is_not_drawn_by_itself_even_outside_defs():
    drawing = read_svg(svg('<symbol id="s"><path id="p" d="M 0 0 L 10 0"/></symbol>'
                           '<use id="a" href="#s" x="1"/><use id="b" href="#s" y="2"/>'))
    assert ends(drawing) == {"a": ([1.0, 0.0], [11.0, 0.0]), "b": ([0.0, -2.0], [10.0, -2.0])}
    assert any("SVG does not draw by themselves" in n and "<symbol id='s'>" in n for n in drawing.notes)
    with pytest.raises(DrawingError, match=r"no paths found .*does not draw by themselves.*<symbol id='s'>"):
        read_svg(svg('<symbol id="s"><path d="M 0 0 L 10 0"/></symbol>'))


def test_use_of_a_group_with_transforms_on_the_way():
    # point p -> group translate(1,2) -> use's x: translate(3,0) -> use's transform rotate(90) -> flip y
    drawing = read_svg(svg('<defs><g id="grp" transform="translate(1,2)"><path d="M 0 0 L 1 0"/>'
                           '<circle cx="0" cy="0" r="1"/></g></defs>'
                           '<use id="u" href="#grp" transform="rotate(90)" x="3"/>'))
    line, circle = drawing.paths
    assert (line.name, circle.name) == ("u#1", "u#2")  # what one <use> draws is named after it
    np.testing.assert_allclose([line.pieces[0].start, line.pieces[0].end], [[-2, -4], [-2, -5]], atol=1e-12)
    assert circle.closed and all(isinstance(p, EllipticArcPiece) for p in circle.pieces)
    np.testing.assert_allclose(np.hypot(*(np.hstack([p.point(np.linspace(0, 1, 9)) for p in circle.pieces])
                                          - np.array([[-2.0], [-4.0]]))), 1.0, atol=1e-12)
    assert read_svg(svg('<defs><g id="grp"><path d="M 0 0 L 1 0"/></g></defs><use href="#grp"/>'
                        )).selected(["use-1"]).paths[0].name == "use-1"


def test_nested_use_and_a_use_of_a_plain_element():
    drawing = read_svg(svg('<defs><path id="p" d="M 0 0 L 2 0"/><use id="inner" href="#p" x="1"/></defs>'
                           '<use id="outer" href="#inner" y="3"/><path id="q" d="M 0 10 L 1 10"/>'
                           '<use id="again" href="#q" transform="scale(2)"/>'))
    assert ends(drawing) == {"outer": ([1.0, -3.0], [3.0, -3.0]), "q": ([0.0, -10.0], [1.0, -10.0]),
                             "again": ([0.0, -20.0], [2.0, -20.0])}


def test_a_symbol_viewbox_is_fitted_to_the_use_width_and_height():
    drawing = read_svg(svg('<symbol id="i" viewBox="0 0 24 24"><path d="M 0 12 L 24 12"/></symbol>'
                           '<use id="big" href="#i" x="100" width="48" height="48"/>'
                           '<use id="wide" href="#i" y="100" width="96" height="48"/>', viewBox="0 0 200 200"))
    # 48/24 = 2: the line at y=12 lands at y=24; 96x48 keeps the aspect ratio (meet) and centres it
    assert ends(drawing) == {"big": ([100.0, -24.0], [148.0, -24.0]), "wide": ([24.0, -124.0], [72.0, -124.0])}


def test_a_use_cycle_and_a_use_bomb_are_refused_quickly():
    with pytest.raises(DrawingError, match=r"<use> .*draws itself through <use> references"):
        read_svg(svg('<g id="a"><path d="M 0 0 L 1 1"/><use href="#a"/></g>'))
    with pytest.raises(DrawingError, match=r"<use id='u'> \(href='#u'\) draws itself"):
        read_svg(svg('<use id="u" href="#u"/><path d="M 0 0 L 1 1"/>'))
    levels = ['<path id="l0" d="M 0 0 L 1 1"/>'] + [
        f'<g id="l{k}">' + "".join(f'<use href="#l{k - 1}" x="{i}"/>' for i in range(10)) + "</g>" for k in range(1, 10)]
    started = time.perf_counter()
    with pytest.raises(DrawingError, match=r"expands to more than 100000 elements"):
        read_svg(svg("<defs>" + "".join(levels) + '</defs><use href="#l9"/>'))
    assert time.perf_counter() - started < 10


# --- CSS, display, visibility, paint ---------------------------------------------------------------------

def test_a_style_sheet_hides_a_class_and_paints_another():
    drawing = read_svg(svg('<defs><style>.hidden { display: none } .ink { stroke: #c00 }</style></defs>'
                           '<path id="gone" class="hidden" d="M 0 0 L 100 0"/>'
                           '<path id="kept" class="ink other" fill="none" d="M 0 0 L 10 0"/>'
                           '<path id="frame" fill="none" d="M 0 0 L 50 50"/>'))
    assert [p.name for p in drawing.paths] == ["kept"]
    assert any("hidden" in n and "'gone'" in n for n in drawing.notes)
    assert any("paint nothing" in n and "'frame'" in n for n in drawing.notes)


def test_style_rules_that_are_not_applied_are_named():
    drawing = read_svg(svg('<style>/* g x {} */ g.off path { display: none } .frame > rect, a[href] {fill: none}'
                           ' .hidden, path, #id, *, path.ink { stroke: black } @media print { path { stroke: red } }'
                           '</style><g class="off"><path id="p" d="M 0 0 L 10 0"/></g>'))
    assert [p.name for p in drawing.paths] == ["p"]  # read as if the rule were absent, and said so
    [note] = [n for n in drawing.notes if "not applied" in n]
    for selector in ("'g.off path'", "'.frame > rect'", "'a[href]'"):
        assert selector in note
    for applied in ("'.hidden'", "'path'", "'#id'", "'*'", "'path.ink'", "@media", "g x"):
        assert applied not in note
    plain = read_svg(svg('<style>.a { stroke: black } path { fill: none }</style><path id="p" d="M 0 0 L 10 0"/>'))
    assert not any("not applied" in n for n in plain.notes)


def test_a_tabler_style_icon_skips_its_bounding_rect():
    icon = ('<svg xmlns="http://www.w3.org/2000/svg" width="24" height="24" viewBox="0 0 24 24" fill="none" '
            'stroke="currentColor" stroke-width="2" stroke-linecap="round" stroke-linejoin="round">'
            '<path stroke="none" d="M0 0h24v24H0z" fill="none"/>'
            '<path d="M12 12m-9 0a9 9 0 1 0 18 0a9 9 0 1 0 -18 0"/></svg>')
    drawing = read_svg(icon)
    (path,) = drawing.paths
    assert path.name == "path-2" and path.closed and len(path.pieces) == 2
    for piece in path.pieces:
        assert isinstance(piece, EllipticArcPiece) and piece.rx == pytest.approx(9) and piece.ry == pytest.approx(9)
        np.testing.assert_allclose(piece.centre, [12.0, -12.0], atol=1e-12)
    assert drawing.bbox() == pytest.approx((3.0, -21.0, 21.0, -3.0))


def test_hidden_and_invisible_uses():
    body = ('<defs><path id="p" d="M 0 0 L 1 0"/></defs><use id="a" href="#p" style="display:none"/>'
            '<g visibility="hidden"><use id="b" href="#p"/><use id="c" href="#p" y="2" visibility="visible"/></g>')
    assert [p.name for p in read_svg(svg(body)).paths] == ["c"]


def test_switch_draws_its_first_child_without_conditions_and_a_links_children():
    drawing = read_svg(svg('<switch><g systemLanguage="xx"><path id="xx" d="M 0 0 L 1 0"/></g>'
                           '<g><path id="plain" d="M 0 1 L 1 1"/></g><path id="later" d="M 0 2 L 1 2"/></switch>'
                           '<a href="https://example.org"><path id="linked" d="M 0 3 L 1 3"/></a>'))
    assert [p.name for p in drawing.paths] == ["plain", "linked"]


# --- units and viewports ---------------------------------------------------------------------------------

def test_lengths_in_units_are_user_units_at_96_per_inch():
    drawing = read_svg(svg('<circle id="c" cx="10mm" cy="20mm" r="5mm"/><line id="l" x1="0" y1="0" x2="1in" y2="0"/>'
                           '<rect id="r" x="1cm" y="0" width="72pt" height="6pc"/>', width="60mm", height="60mm"))
    circle, line, rect = drawing.paths
    for piece in circle.pieces:  # svgelements takes 1 mm as 0.0393701 in: 5e-7 off
        assert piece.centre == pytest.approx((10 * MM, -20 * MM), rel=1e-6)
        assert piece.rx == pytest.approx(5 * MM, rel=1e-6) and piece.ry == pytest.approx(5 * MM, rel=1e-6)
    assert line.length() == pytest.approx(96.0, rel=1e-12)
    assert rect.length() == pytest.approx(2 * 96 + 2 * 96, rel=1e-12)  # 72 pt = 6 pc = 1 in = 96
    assert rect.pieces[0].start.tolist() == pytest.approx([10 * MM, 0.0], rel=1e-6)
    assert any("60mm" in n for n in drawing.notes)


def test_the_page_size_does_not_scale_the_user_units():
    drawing = read_svg(svg('<circle id="c" cx="30" cy="15" r="10"/>', width="60mm", height="40mm", viewBox="0 0 60 30"))
    for piece in drawing.paths[0].pieces:
        np.testing.assert_allclose(piece.centre, [30.0, -15.0], atol=1e-12)
        assert piece.rx == pytest.approx(10.0, rel=1e-14) and piece.ry == pytest.approx(10.0, rel=1e-14)


def test_nested_svg_viewports():
    drawing = read_svg(svg('<svg x="10" y="20" width="50" height="50" viewBox="0 0 10 10"><path id="in" d="M 0 0 L 10 10"/>'
                           '</svg><svg x="5" y="6"><path id="moved" d="M 0 0 L 1 0"/></svg>', viewBox="0 0 100 100"))
    assert ends(drawing) == {"in": ([10.0, -20.0], [60.0, -70.0]), "moved": ([5.0, -6.0], [6.0, -6.0])}


def test_an_empty_nested_viewport_is_an_error_not_a_silent_loss():
    with pytest.raises(DrawingError, match=r"an <svg> element has a viewBox and zero width or height"):
        read_svg(svg('<path d="M 0 0 L 1 1"/><svg width="0" height="10" viewBox="0 0 1 1"><path d="M 0 0 L 1 0"/></svg>'
                     '<path d="M 0 5 L 1 5"/>'))


def test_a_path_without_data_is_named_not_reported_as_a_library_error():
    """A <path> whose d a script was to fill in (the corpus's rhodonea): svgelements raises a
    TypeError on it; the message names the path and says what to do."""
    with pytest.raises(DrawingError, match=r"<path id='p1'> has no path data \(no d attribute\).*script"):
        read_svg(svg('<path id="p1" stroke="#fff" fill="none"/><path d="M 0 0 L 1 1" stroke="black"/>'))


# --- hostile and unusual XML ------------------------------------------------------------------------------

BOMB = ('<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY a "aaaaaaaaaa">'
        + "".join(f'<!ENTITY {chr(98 + k)} "{("&" + chr(97 + k) + ";") * 10}">' for k in range(8))
        + ']><svg xmlns="http://www.w3.org/2000/svg"><title>&i;</title><path d="M 0 0 L 1 1"/></svg>')


def test_an_xml_bomb_is_refused_at_once():
    started = time.perf_counter()
    with pytest.raises(DrawingError, match=r"declares the XML entity 'a' .*XML bomb"):
        read_svg(BOMB)
    assert time.perf_counter() - started < 1


def test_an_external_entity_is_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("M 0 0 L 1 1")
    doc = (f'<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY x SYSTEM "file://{secret}">]>'
           '<svg xmlns="http://www.w3.org/2000/svg"><path d="&x;"/></svg>')
    with pytest.raises(DrawingError, match=rf"declares the XML entity 'x' .*refers to 'file://{secret}'"):
        read_svg(doc)
    with pytest.raises(DrawingError, match=r"refers to 'file:///etc/passwd'"):
        read_svg('<!DOCTYPE svg [<!ENTITY x SYSTEM "file:///etc/passwd">]><svg><title>&x;</title></svg>')


ILLUSTRATOR = ('<?xml version="1.0" encoding="utf-8"?>\n<!-- Generator: Adobe Illustrator 24.0.0, SVG Export Plug-In -->\n'
               '<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd" [\n'
               '\t<!ENTITY ns_extend "http://ns.adobe.com/Extensibility/1.0/">\n'
               '\t<!ENTITY ns_ai "http://ns.adobe.com/AdobeIllustrator/10.0/">\n'
               '\t<!-- the namespaces, as Illustrator declares them -->\n'
               '\t<!ENTITY ns_svg "http://www.w3.org/2000/svg">\n'
               "\t<!ENTITY ns_xlink 'http://www.w3.org/1999/xlink'>\n"
               ']>\n<svg version="1.1" xmlns:x="&ns_extend;" xmlns:i="&ns_ai;" xmlns="&ns_svg;" xmlns:xlink="&ns_xlink;" '
               'viewBox="0 0 20 10"><path fill="none" stroke="#000" d="M 0 0 L 10 0 L 20 10"/></svg>\n')


def test_an_illustrator_doctype_with_namespace_entities_is_read(tmp_path):
    """Issue 17: Illustrator's exports declare their namespaces as entities, which the safe parser refuses."""
    file = tmp_path / "ai.svg"
    file.write_text(ILLUSTRATOR, encoding="utf-8")
    for source in (file, ILLUSTRATOR):
        d = read_svg(source)
        assert len(d.paths) == 1 and np.allclose(d.paths[0].pieces[-1].end, [20.0, -10.0])
        assert any("inlined the XML entities ns_ai, ns_extend, ns_svg, ns_xlink" in n for n in d.notes)


@pytest.mark.parametrize("doctype, why", [
    ('<!ENTITY a "x"><!ENTITY b "&a;&a;">', "nests"),
    ('<!ENTITY x SYSTEM "file:///etc/passwd">', "external"),
    ('<!ENTITY % p "x">', "a parameter entity"),
    ('<!ENTITY a "x"><!ELEMENT svg ANY>', "another declaration"),
    ('<!ENTITY a "' + "x" * 2000 + '">', "too long a value"),
    ("".join(f'<!ENTITY e{k} "x">' for k in range(65)), "too many"),
])
def test_only_plain_text_entities_are_inlined(doctype, why):
    from skatetrace.drawings.svg_entities import inline_entities

    doc = f'<!DOCTYPE svg [{doctype}]><svg xmlns="http://www.w3.org/2000/svg"><title>&a;</title></svg>'
    assert inline_entities(doc) == (doc, []), why
    assert inline_entities(doc.encode()) == (doc.encode(), []), why
    with pytest.raises(DrawingError, match="refused"):
        read_svg(doc)


def test_inlining_is_bounded_in_the_size_it_adds():
    from skatetrace.drawings.svg_entities import MAX_GROWTH, inline_entities

    value = "y" * 1000
    refs = "&a;" * (MAX_GROWTH // 1000 + 1)
    doc = f'<!DOCTYPE svg [<!ENTITY a "{value}">]><svg><title>{refs}</title></svg>'
    assert inline_entities(doc) == (doc, [])  # more than MAX_GROWTH characters would be added
    small = f'<!DOCTYPE svg [<!ENTITY a "{value}">]><svg><title>&a;&a;</title></svg>'
    out, names = inline_entities(small)
    assert names == ["a"] and out == f"<svg><title>{value}{value}</title></svg>"


def test_a_plain_doctype_is_fine_and_so_is_a_file_without_the_namespace(tmp_path):
    doctype = ('<?xml version="1.0" standalone="no"?>\n<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" '
               '"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd">\n')
    file = tmp_path / "old.svg"
    file.write_text(doctype + '<svg version="1.1"><defs><symbol id="s"><path d="M 0 0 L 3 4"/></symbol></defs>'
                    '<use href="#s" x="1"/></svg>')
    assert ends(read_svg(file)) == {"use-1": ([1.0, 0.0], [4.0, -4.0])}


def test_a_drawing_arc_stays_exact_through_a_reflected_use():
    # matrix(0 1 1 0) swaps x and y: the quarter circle from (1,0) to (0,1) maps onto itself
    drawing = read_svg(svg('<defs><path id="q" d="M 1 0 A 1 1 0 0 1 0 1"/></defs>'
                           '<use href="#q" transform="matrix(0 1 1 0 0 0)"/>'))
    (piece,) = drawing.paths[0].pieces
    h = math.sqrt(0.5)
    np.testing.assert_allclose(piece.point([0.0, 0.5, 1.0]), [[0.0, h, 1.0], [-1.0, -h, 0.0]], atol=1e-15)


def test_an_element_with_its_own_transform_inside_a_transformed_group_is_read():
    """svgelements writes the group's transform before the element's own: the element is still found
    (a Bootstrap icon's flipped rect was reported as having no extent)."""
    svg = ('<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 16 16"><g transform="translate(1,2)">'
           '<rect width="4" height="12" rx="1" transform="matrix(1 0 0 -1 6 15)"/></g></svg>')
    drawing = read_svg(svg)
    assert len(drawing.paths) == 1
    # x: 1 + 6 + [0, 4]; y on the page: 2 + 15 - [0, 12], flipped to point up
    np.testing.assert_allclose(drawing.bbox(), [7.0, -17.0, 11.0, -5.0], atol=1e-12)


# --- repeated small shapes ------------------------------------------------------------------------


def test_a_grid_of_dots_is_one_shape_of_few_arcs_traced_once(tmp_path):
    # Nine dots as icon sets draw them (Adwaita's view-app-grid: four cubics each, in relative
    # commands) at 6 m / 1 mm. Each dot was fitted by 32 arcs whatever the tolerance, the nine fits
    # differed by round-off and were traced as 5 to 9 distinct sections, and controls.csv got 9.1
    # million rows (37 s on the command line). Now: a few arcs a dot, one shape, traced once.
    import skatetrace as st
    from skatetrace.pipeline import trace_and_verify

    dot = "c -0.554688 0 -1 0.445312 -1 1 s 0.445312 1 1 1 s 1 -0.445312 1 -1 s -0.445312 -1 -1 -1 z"
    d = " ".join(f"M {x} {y} {dot}" for y in (3, 7, 11) for x in (4, 8, 12))
    (tmp_path / "grid.svg").write_text(svg(f'<path d="{d}"/>', viewBox="0 0 16 16", width="16", height="16"))
    fig = st.resolve(tmp_path / "grid.svg", size="6m", tol="1mm", height=1.7).figure
    assert len(fig.curves) == 9 and all(len(c.pieces) <= 8 for c in fig.curves)
    done = trace_and_verify(fig, fig.params, st.TraceOptions(speed=2.0))
    assert done.success, done.message
    assert len({id(s.phases) for s in done.trace.sections}) == 1
    assert done.schedule.t.size < 2_000_000


def test_a_near_cusp_of_a_quarter_of_the_tolerance_is_a_rest_and_the_figure_traces(tmp_path):
    # The Rust documentation's favicon's "D" (see test_splitting): with its tip of 0.126 mm at 6 m a
    # cusp, its long run is two sections, each traced; kept smooth, the section through the tip
    # failed ("no stop of length 3.10 found", 31 s)
    import skatetrace as st
    from skatetrace.pipeline import trace_and_verify

    d = ("M59.6,122.8L73.8,80c0,0,7,0,10.8,0s28.8-1.7,25.4,17.5c-3.4,19.2-18.8,25.2-36.8,25.4"
         "S59.6,122.8,59.6,122.8z")
    (tmp_path / "d.svg").write_text(svg(f'<path d="{d}"/><path d="M0 0 H 199.7 V 184.2 H 0 Z" fill="none" '
                                        'stroke="black"/>', viewBox="0 0 199.7 184.2"))
    fig = st.resolve(tmp_path / "d.svg", size="6m", tol="1mm").figure
    assert [len(c.sections()) for c in fig.curves] == [3, 4]
    done = trace_and_verify(fig, fig.params, st.TraceOptions(speed=2.0), rests="never")
    assert done.success, done.message


def test_a_logo_whose_petals_end_in_tips_of_143_degrees_traces_without_rests(tmp_path):
    # simple-icons' CorelDRAW logo (see test_splitting) at 6 m / 1 mm: its outer petals' tips were
    # fitted by arcs of a millimetre and failed, then nine rounds of rests cut its curves into
    # sections of millimetres, two of which nothing traced (62 s, verification failed). With the
    # tips reversals, every section traces at once and the replay verifies.
    import skatetrace as st
    from skatetrace.pipeline import trace_and_verify
    from test_splitting import CORELDRAW

    (tmp_path / "coreldraw.svg").write_text(svg(f'<path d="{CORELDRAW}"/>', viewBox="0 0 24 24"))
    fig = st.resolve(tmp_path / "coreldraw.svg", size="6m", tol="1mm", height=1.7).figure
    done = trace_and_verify(fig, fig.params, st.TraceOptions(speed=2.0), rests="never")
    assert done.success, done.message
    assert done.report.max_deviation <= 1e-6 * 6.0
