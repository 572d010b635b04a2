"""A survey in flight, as data: what each drone was given and has flown, its photos, the
area they cover and the hand-over of a lost drone's lanes. Pure: the survey service feeds
it the vehicles' events and states, stores it and sends the missions it builds."""
