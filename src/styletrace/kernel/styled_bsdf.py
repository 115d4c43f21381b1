"""`styled`: a BSDF wrapper that assigns a style to the objects using it.

    <bsdf type="styled">
        <string name="style" value="cel"/>
        <string name="levels" value="0.3,0.9"/>
        <bsdf type="diffuse"/>
    </bsdf>

Properties: `style` (required), the style's parameters, `inner_samples` and `estimator` (as on the
`stylized` integrator), and exactly one nested BSDF, to which every light-transport query is
forwarded. The `stylized` integrator applies the style where paths meet these objects (its
`stylize` property); other integrators render them physically based.
"""
from __future__ import annotations

from styletrace.config.settings import parse_slot
from styletrace.errors import SettingsError
from styletrace.gate import mi


class StyledBSDF(mi.BSDF):
    """The `styled` BSDF (module docstring): every query goes to the nested BSDF.

    Args:
        props: `style`, the style's parameters, `inner_samples`, `estimator`, one nested BSDF.

    Raises:
        SettingsError: not exactly one nested BSDF, no `style`, or a bad style setting.
    """
    def __init__(self, props: mi.Properties):
        super().__init__(props)
        nested, values = [], {}
        for key in props.keys():
            value = props[key]
            if isinstance(value, mi.BSDF):
                nested.append(value)
            else:
                values[key] = value
        if len(nested) != 1:
            raise SettingsError(
                f"a 'styled' BSDF needs exactly one nested BSDF, found {len(nested)}"
            )
        if "style" not in values:
            raise SettingsError("a 'styled' BSDF needs a 'style' property")
        self.nested = nested[0]
        self.slot = parse_slot(values, context="a 'styled' BSDF")
        self.m_flags = self.nested.m_flags
        self.m_components = list(self.nested.m_components)

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self.nested.sample(ctx, si, sample1, sample2, active)

    def eval(self, ctx, si, wo, active=True):
        return self.nested.eval(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return self.nested.pdf(ctx, si, wo, active)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.nested.eval_pdf(ctx, si, wo, active)

    def eval_pdf_sample(self, ctx, si, wo, sample1, sample2, active=True):
        return self.nested.eval_pdf_sample(ctx, si, wo, sample1, sample2, active)

    def eval_null_transmission(self, si, active=True):
        return self.nested.eval_null_transmission(si, active)

    def eval_diffuse_reflectance(self, si, active=True):
        return self.nested.eval_diffuse_reflectance(si, active)

    def traverse(self, callback):
        self.nested.traverse(callback)

    def to_string(self):
        return f"StyledBSDF[{self.slot.style.describe()}, nested={self.nested}]"
