"""A small scene on a film with Mitsuba's default reconstruction filter (a gaussian), as an XML
file's text."""

#: a sphere on a floor under an area light, on a film with no rfilter: Mitsuba's default, a gaussian
GAUSSIAN_SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world">
      <lookat origin="0, 1.2, 4" target="0, 0.4, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm">
      <integer name="width" value="24"/><integer name="height" value="24"/></film></sensor>
  <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="0.5"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.1"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.6"/></bsdf></shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="90"/><translate y="2.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="6, 6, 6"/></emitter></shape>
</scene>
"""
