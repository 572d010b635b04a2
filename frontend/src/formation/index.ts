// The dashboard's formation panel on the map: leader, followers, shape and route, flown
// and watched (backend/formation/routes.py).
export { FormationPanel } from "./panel";
import "./formation.css";
